"""What a call raises, for tests that compare palaestra's exception with a reference library's
on the same input."""

from __future__ import annotations

import warnings
from collections.abc import Callable
from typing import Any


def raised(fn: Callable[[], Any]) -> BaseException | None:
    """The exception ``fn()`` raises (warnings silenced: the reference libraries warn on the
    bad inputs these tests feed them), or None when it returns."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        try:
            fn()
        except Exception as e:
            return e
    return None
