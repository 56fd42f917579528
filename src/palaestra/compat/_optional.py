"""The error raised when Gymnasium, which only ``palaestra.compat`` uses, is missing."""

from __future__ import annotations

from palaestra.error import DependencyNotInstalled


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
