"""Remember a wrapper's constructor arguments so that ``env.spec`` can rebuild the stack."""

from __future__ import annotations

from copy import deepcopy
from typing import Any


class RecordConstructorArgs:
    """Mixin that stores the keyword arguments of the first ``__init__`` that calls it.

    Call ``RecordConstructorArgs.__init__(self, ...)`` before the wrapper's own ``__init__``:
    only the first call records, so a subclass's arguments win over its parent's.
    """

    _saved_kwargs: dict[str, Any]

    def __init__(self, *, _disable_deepcopy: bool = False, **kwargs: Any) -> None:
        if not hasattr(self, "_saved_kwargs"):
            self._saved_kwargs = kwargs if _disable_deepcopy else deepcopy(kwargs)
