"""Build a torch optimizer without importing torch's compiler.

``torch.optim.Optimizer``'s ``add_param_group`` (called by ``__init__``), ``zero_grad``,
``state_dict`` and ``load_state_dict`` are wrapped by ``torch._disable_dynamo``, which imports
``torch._dynamo`` on the first call (with sympy, parts of ``torch._inductor`` and
``torch.distributed``: 1-3 s on a 2-core machine, more than building the rest of a model) only
to mark the method as one the compiler must not trace. While ``torch._dynamo`` has not been
imported, nothing can be compiling and no frame-evaluation hook is installed, so what the
wrapper does around the call (turn that hook off, put it back) changes nothing: calling the
function it wraps gives the same result, bit for bit.

``build_optimizer`` therefore gives the optimizer it builds instance-level versions of those
methods that call torch's function directly while ``torch._dynamo`` is absent from
``sys.modules``, and torch's own wrapped method as soon as it is present (a user who compiles
gets torch's behaviour). Nothing global changes: torch's classes and functions are untouched,
other optimizers are plain torch, and copies and pickles of this one (``Optimizer.__getstate__``
keeps only its state) are plain torch optimizers. A method is handled this way only when the
class inherits torch's exact wrapper (same code as ``torch._disable_dynamo`` makes, with the
wrapped function under ``__wrapped__``); a subclass's own method, or a torch whose wrapper
differs, keeps torch's path.
"""

from __future__ import annotations

import functools
import sys
import types
from collections.abc import Callable
from typing import Any

import torch

__all__ = ["build_optimizer"]

_COMPILER = "torch._dynamo"
# The methods torch.optim.Optimizer wraps with torch._disable_dynamo (torch 2.1 to 2.13).
_WRAPPED = ("add_param_group", "zero_grad", "state_dict", "load_state_dict")


def _lazy_wrapper_code() -> Any:
    """The code object of torch's lazy-import wrapper (None where torch has no such API)."""
    disable = getattr(torch, "_disable_dynamo", None)
    if disable is None:
        return None
    return getattr(disable(lambda: None), "__code__", None)


def _until_compiler_loaded(wrapped: Callable[..., Any], plain: Callable[..., Any]) -> Any:
    """A method calling ``plain`` while torch's compiler is not imported, ``wrapped`` after."""

    @functools.wraps(plain)
    def method(self: torch.optim.Optimizer, *args: Any, **kwargs: Any) -> Any:
        if _COMPILER in sys.modules:
            return wrapped(self, *args, **kwargs)
        return plain(self, *args, **kwargs)

    return method


def _plain_methods(optimizer_class: type[torch.optim.Optimizer]) -> tuple[tuple[str, Any], ...]:
    """(name, method) for each of ``_WRAPPED`` that ``optimizer_class`` inherits from torch."""
    code = _lazy_wrapper_code()
    found = []
    for name in _WRAPPED:
        wrapped: Any = getattr(optimizer_class, name, None)
        torch_own: Any = getattr(torch.optim.Optimizer, name, None)
        plain = getattr(wrapped, "__wrapped__", None)
        if (
            code is not None
            and wrapped is torch_own
            and getattr(wrapped, "__code__", None) is code
            and callable(plain)
        ):
            found.append((name, _until_compiler_loaded(wrapped, plain)))
    return tuple(found)


def build_optimizer(
    optimizer_class: type[torch.optim.Optimizer], params: Any, **kwargs: Any
) -> torch.optim.Optimizer:
    """``optimizer_class(params, **kwargs)``, built and used without importing torch's compiler
    (see the module docstring); the same object torch builds, with the same state."""
    methods = _plain_methods(optimizer_class)
    if _COMPILER in sys.modules or not methods:
        return optimizer_class(params, **kwargs)
    optimizer = optimizer_class.__new__(optimizer_class)
    for name, method in methods:
        # Set before __init__, which calls self.add_param_group.
        setattr(optimizer, name, types.MethodType(method, optimizer))
    optimizer_class.__init__(optimizer, params, **kwargs)
    return optimizer
