"""What ``palaestra.compat`` needs before Gymnasium is imported: the error raised when it is
missing, the id prefix of Gymnasium's registry, and the spec fields both libraries share."""

from __future__ import annotations

from typing import Any

from palaestra.error import DependencyNotInstalled

# "gymnasium:Taxi-v4" is Gymnasium's Taxi-v4 (palaestra.compat.registry makes it).
GYMNASIUM_PREFIX = "gymnasium:"


def gymnasium_missing(
    purpose: str = "palaestra.compat's Gymnasium interop",
) -> DependencyNotInstalled:
    """``DependencyNotInstalled`` naming the ``pip install`` that fixes it.

    >>> str(gymnasium_missing("reading Taxi"))
    'gymnasium is not installed, run `pip install gymnasium` (needed for reading Taxi)'
    """
    # gymnasium is not a palaestra extra: the user installs the library they want to talk to.
    return DependencyNotInstalled(
        f"gymnasium is not installed, run `pip install gymnasium` (needed for {purpose})"
    )


def shared_spec_fields(spec: Any) -> dict[str, Any]:
    """The fields of ``spec`` (Gymnasium's ``EnvSpec`` or palaestra's) that a spec of the other
    library takes as they are, all but the id; ``kwargs`` is a fresh dict."""
    return dict(
        entry_point=spec.entry_point,
        reward_threshold=spec.reward_threshold,
        nondeterministic=spec.nondeterministic,
        max_episode_steps=spec.max_episode_steps,
        order_enforce=spec.order_enforce,
        disable_env_checker=spec.disable_env_checker,
        kwargs=dict(spec.kwargs),
    )
