"""What ``palaestra.compat`` needs before Gymnasium is imported: the error raised when it is
missing, and the id prefix of Gymnasium's registry."""

from __future__ import annotations

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
