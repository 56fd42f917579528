"""``EzPickle``: objects pickled as the arguments of their constructor (Gymnasium's helper)."""

from __future__ import annotations

from typing import Any

__all__ = ["EzPickle"]


class EzPickle:
    """A mixin for objects that hold what pickle cannot (a physics engine, a C handle): the
    pickle keeps the constructor's arguments, and unpickling builds a new object from them.

    >>> import copy
    >>> class Dog(EzPickle):
    ...     def __init__(self, colour, tail="bushy"):
    ...         EzPickle.__init__(self, colour, tail=tail)
    ...         self.colour, self.tail = colour, tail
    >>> dog = copy.deepcopy(Dog("brown", tail="short"))  # pickle takes the same path
    >>> dog.colour, dog.tail
    ('brown', 'short')

    The new object is freshly constructed: state changed after ``__init__`` is not kept.
    """

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        self._ezpickle_args = args
        self._ezpickle_kwargs = kwargs

    def __getstate__(self) -> dict[str, Any]:
        """The constructor's arguments."""
        return {"_ezpickle_args": self._ezpickle_args, "_ezpickle_kwargs": self._ezpickle_kwargs}

    def __setstate__(self, state: dict[str, Any]) -> None:
        """Become a new object built from the stored arguments."""
        fresh = type(self)(*state["_ezpickle_args"], **state["_ezpickle_kwargs"])
        self.__dict__.update(fresh.__dict__)
