"""Python-literal strings in settings files, read as data without ``eval``.

RL Zoo hyperparameter files write some values as Python source: ``policy_kwargs: "dict(
net_arch=[64, 64], activation_fn=nn.ReLU, ortho_init=False)"``, ``normalize: "{'norm_obs':
False}"``. The Zoo runs them through ``eval``, so a file could run any code; palaestra reads
them with :func:`literal`, which walks the syntax tree and accepts only what such files hold:

- literals: numbers (with a sign), strings, ``True``/``False``/``None``, lists, tuples (read as
  lists, as JSON keeps them) and dicts with string keys;
- ``dict(key=value, ...)`` with keyword arguments only;
- a dotted name the caller's table holds (``nn.ReLU`` -> ``"relu"``, from
  :mod:`palaestra.runs.known_names`).

Anything else (another call such as ``__import__('os')``, an attribute of a value, an
operator, a subscript, a comprehension, a name the table lacks) is a :class:`RunError` naming
the piece refused and the whole text.
"""

from __future__ import annotations

import ast
from collections.abc import Mapping
from typing import Any

from palaestra.runs.errors import RunError

__all__ = ["MAX_LENGTH", "literal"]

MAX_LENGTH = 10_000  # characters: the Zoo's longest value is a few hundred
_CONSTANTS = (int, float, str, bool, type(None))


def literal(text: str, what: str, names: Mapping[str, Any]) -> Any:
    """The data ``text`` writes, for the setting ``what`` (named in errors); dotted names
    resolve through ``names``.

    >>> literal("dict(net_arch=[64, 64], activation_fn=nn.ReLU)", "policy_kwargs",
    ...         {"nn.ReLU": "relu"})
    {'net_arch': [64, 64], 'activation_fn': 'relu'}
    >>> literal("{'norm_obs': False, 'clip_obs': -1e1}", "normalize", {})
    {'norm_obs': False, 'clip_obs': -10.0}
    """
    if len(text) > MAX_LENGTH:
        raise RunError(
            f"{what}: a Python literal of {len(text):,} characters is refused "
            f"(at most {MAX_LENGTH:,})",
            "write the value as YAML",
        )
    source = text.strip()
    try:
        tree = ast.parse(source, mode="eval")
    except SyntaxError as exc:
        raise RunError(
            f"{what}: {text!r} is not a Python literal: {exc.msg}", "fix the value"
        ) from None
    except (MemoryError, RecursionError, ValueError):
        raise RunError(f"{what}: {text!r} is not a Python literal", "fix the value") from None
    try:
        return _Reader(source, what, names).read(tree.body)
    except RecursionError:
        raise RunError(f"{what}: {text!r} nests too deeply", "fix the value") from None


class _Reader:
    """One walk over one value's tree."""

    def __init__(self, source: str, what: str, names: Mapping[str, Any]) -> None:
        self.source, self.what, self.names = source, what, names

    def refuse(self, node: ast.AST, why: str) -> RunError:
        piece = ast.get_source_segment(self.source, node) or type(node).__name__
        allowed = ", ".join(sorted(self.names)) or "none"
        return RunError(
            f"{self.what}: {piece!r} in {self.source!r} is refused: {why}",
            "write literals, lists, {...} or dict(key=value) only, and names among: " + allowed,
        )

    def read(self, node: ast.AST) -> Any:
        if isinstance(node, ast.Constant) and isinstance(node.value, _CONSTANTS):
            return node.value
        if isinstance(node, ast.UnaryOp) and isinstance(node.op, (ast.USub, ast.UAdd)):
            operand = node.operand
            if (
                isinstance(operand, ast.Constant)
                and isinstance(operand.value, (int, float))
                and not isinstance(operand.value, bool)
            ):
                return -operand.value if isinstance(node.op, ast.USub) else operand.value
            raise self.refuse(node, "a sign applies to a number only")
        if isinstance(node, (ast.List, ast.Tuple)):
            return [self.read(item) for item in node.elts]
        if isinstance(node, ast.Dict):
            return self.mapping(node, list(zip(node.keys, node.values)))
        if isinstance(node, ast.Call):
            return self.call(node)
        if isinstance(node, (ast.Name, ast.Attribute)):
            return self.name(node)
        raise self.refuse(node, f"{type(node).__name__} is not data")

    def mapping(self, node: ast.AST, items: list[tuple[ast.expr | None, ast.expr]]) -> Any:
        out: dict[str, Any] = {}
        for key, value in items:
            if key is None:
                raise self.refuse(node, "** unpacking is not data")
            name = self.read(key)
            if not isinstance(name, str):
                raise self.refuse(key, "a key must be a string")
            out[name] = self.read(value)
        return out

    def call(self, node: ast.Call) -> Any:
        if not (isinstance(node.func, ast.Name) and node.func.id == "dict"):
            raise self.refuse(node, "the only call allowed is dict(key=value, ...)")
        if node.args:
            raise self.refuse(node, "dict(...) takes keyword arguments only")
        keys: list[ast.expr | None] = [
            None if k.arg is None else ast.Constant(k.arg) for k in node.keywords
        ]
        return self.mapping(node, list(zip(keys, [k.value for k in node.keywords])))

    def name(self, node: ast.Name | ast.Attribute) -> Any:
        parts: list[str] = []
        cursor: ast.expr = node
        while isinstance(cursor, ast.Attribute):
            parts.append(cursor.attr)
            cursor = cursor.value
        if not isinstance(cursor, ast.Name):
            raise self.refuse(node, "an attribute of a value is not data")
        dotted = ".".join([cursor.id, *reversed(parts)])
        if dotted not in self.names:
            raise self.refuse(
                node,
                f"unknown name {dotted!r}, which palaestra.runs.known_names "
                "(docs/known_names.md) does not map",
            )
        return self.names[dotted]
