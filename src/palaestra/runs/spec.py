"""A training run described as data: what ``palaestra train ALGO ENV`` trains, in one object.

A :class:`RunSpec` names the algorithm, the env recipe (id, env kwargs, SB3's Atari recipe,
frame stack, wrapper classes, observation/reward normalization), the policy, the
hyperparameters (the algorithm's constructor keywords, checked against its signature and
against the limits a run folder is held to), the seed and the budget. It is plain JSON: its
:meth:`RunSpec.to_config` is the run folder's ``config.json``, and
:meth:`RunSpec.from_config` reads one back, checked, so a description written on one machine
trains the same run on another.

>>> spec = RunSpec("ppo", "CartPole-v1", n_timesteps=20_000, seed=3)
>>> RunSpec.from_json(spec.to_json()) == spec
True
"""

from __future__ import annotations

import dataclasses
import json
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import palaestra
from palaestra import __version__, error
from palaestra.runs import folder, recipe, settings
from palaestra.runs.errors import RunError

__all__ = ["RunSpec", "resolve_spec"]

# config.json keys that describe where the file came from rather than the run.
_PROVENANCE = ("palaestra_version", "measured")


@dataclasses.dataclass
class RunSpec:
    """One training run: algorithm, env recipe, hyperparameters, seed, budget."""

    algo: str
    env_id: str
    n_timesteps: int = 100_000
    policy: str = "MlpPolicy"
    n_envs: int = 1
    hyperparams: dict[str, Any] = dataclasses.field(default_factory=dict)
    env_kwargs: dict[str, Any] = dataclasses.field(default_factory=dict)
    normalize: bool | dict[str, Any] = False
    env_wrapper: str | dict[str, Any] | list[str | dict[str, Any]] | None = None
    # SB3 callbacks for learn, named as env_wrapper is (palaestra.runs.run_callbacks)
    callback: str | dict[str, Any] | list[str | dict[str, Any]] | None = None
    atari: bool | dict[str, Any] | None = None
    frame_stack: int | None = None
    seed: int | None = None
    device: str = "auto"
    preset: str | None = None
    # sha256 of the files of the user modules the run imports (its env id's, its wrappers'),
    # recorded so that a later eval can warn when they changed
    module_sha256: dict[str, str] = dataclasses.field(default_factory=dict)

    # -- building --------------------------------------------------------------------------
    @classmethod
    def from_preset(
        cls,
        algo: str,
        env_id: str,
        preset: str | None = None,
        *,
        config: str | Path | Mapping[str, Any] | None = None,
        overrides: Mapping[str, Any] | None = None,
        allow_import: Sequence[str] = (),
        **top: Any,
    ) -> RunSpec:
        """The preset for ``algo`` on ``env_id`` (its ``default`` one when it exists, else
        the algorithm's defaults), updated by ``config`` (a settings file or mapping), then
        ``overrides`` (nested settings, e.g. ``{"hyperparams": {"gamma": 0.98}}``), then the
        top-level keywords (``seed=``, ``n_envs=``, ``n_timesteps=``, ``device=``).
        ``allow_import``: the modules a ``config`` file may import."""
        return resolve_spec(
            algo,
            env_id,
            preset,
            config=config,
            overrides=overrides,
            allow_import=allow_import,
            **top,
        )[0]

    @classmethod
    def from_config(
        cls,
        config: Mapping[str, Any],
        source: str = "run description",
        allow_import: Sequence[str] | None = None,
    ) -> RunSpec:
        """A description read back (a run's ``config.json``, a JSON message), checked as a
        run folder is: known keys, types, sizes within limits, hyperparameters the algorithm
        takes. ``allow_import``: the modules its ``env_wrapper``/``env_id`` may import; None
        skips that check (the caller's own description)."""
        data = dict(config)
        folder.check_run_config(data, source, required=("algo", "env_id"))
        if allow_import is not None:
            folder.check_imports(data, source, allow_import)
        for key in _PROVENANCE:
            data.pop(key, None)
        fields = {f.name for f in dataclasses.fields(cls)}
        spec = cls(**{k: v for k, v in data.items() if k in fields})
        spec.algo = spec.algo.lower()
        return spec

    @classmethod
    def from_json(cls, text: str) -> RunSpec:
        """:meth:`to_json`'s inverse."""
        data = json.loads(text)
        if not isinstance(data, dict):
            raise RunError(f"a run description is a JSON object, got {type(data).__name__}")
        return cls.from_config(data)

    def replace(self, **changes: Any) -> RunSpec:
        """A copy with ``changes`` (``spec.replace(seed=4)``)."""
        return dataclasses.replace(self, **changes)

    # -- writing ---------------------------------------------------------------------------
    def to_config(self) -> dict[str, Any]:
        """The run folder's ``config.json``: every setting, the unset optional ones left out,
        and the palaestra version that wrote it."""
        out: dict[str, Any] = {"algo": self.algo, "env_id": self.env_id, "preset": self.preset}
        for key in ("policy", "n_envs", "n_timesteps", "hyperparams", "env_kwargs", "normalize"):
            out[key] = getattr(self, key)
        for key in ("atari", "frame_stack", "env_wrapper", "callback"):
            if getattr(self, key) is not None:
                out[key] = getattr(self, key)
        if self.module_sha256:
            out["module_sha256"] = dict(self.module_sha256)
        out["seed"] = self.seed
        out["device"] = self.device
        out["palaestra_version"] = __version__
        return out

    def to_json(self) -> str:
        """The description as one JSON object (without the version)."""
        data = self.to_config()
        data.pop("palaestra_version")
        return json.dumps(data, sort_keys=True)

    # -- checking --------------------------------------------------------------------------
    def validate(self) -> None:
        """``RunError`` unless the run can be built: a known algorithm and env id, settings of
        usable types, an Atari recipe only on an Atari id, wrappers that are wrapper classes
        (the constructor then checks the hyperparameters; :meth:`from_config` also holds a
        description read from elsewhere to the limits of a run folder)."""
        settings.check_algo(self.algo)
        _check_env_id(self.env_id)
        settings.check_settings(self.to_config(), self.env_id)


def resolve_spec(
    algo: str,
    env_id: str,
    preset: str | None = None,
    *,
    config: str | Path | Mapping[str, Any] | None = None,
    assignments: Sequence[str] = (),
    overrides: Mapping[str, Any] | None = None,
    allow_import: Sequence[str] = (),
    **top: Any,
) -> tuple[RunSpec, list[str]]:
    """:meth:`RunSpec.from_preset` with ``assignments`` (``"key=value"`` strings, as ``--set``
    takes them) and the notes for the user (e.g. that no preset exists); validated, and held
    to a run folder's limits. ``allow_import``: the modules a ``config`` file may import (a
    settings file runs no code otherwise; :mod:`palaestra.runs.folder`). An env id
    ``module:Name-v0`` imports ``module`` (the caller's own request, as ``palaestra.make``)."""
    algo = settings.check_algo(algo)
    _check_env_id(env_id)
    resolved, used, notes = settings.resolve_settings(
        algo, env_id, preset, config, assignments, overrides, allow_import
    )
    unknown = sorted(set(top) - {"seed", "n_envs", "n_timesteps", "device"})
    if unknown:
        raise TypeError(f"unexpected keyword argument(s) {unknown}")
    for key, value in top.items():
        if value is not None:
            resolved[key] = value
    resolved.setdefault("seed", None)
    device = resolved.pop("device", "auto")
    spec = RunSpec(algo=algo, env_id=env_id, preset=used, device=device, **resolved)
    spec.validate()
    try:  # what --set, --n-envs... gave, held to the limits a run folder is held to
        folder.check_run_config(spec.to_config(), "settings", required=())
    except RunError as exc:
        raise RunError(exc.what, "check --set, --n-envs, --timesteps and the config file") from None
    spec.module_sha256 = folder.module_hashes(spec.to_config())
    return spec, notes


def _check_env_id(env_id: str) -> None:
    """``RunError`` for an id no registry holds, with Gymnasium's "did you mean"; an id
    ``module:Name-v0`` imports ``module`` first (the current folder first on the path)."""
    module = recipe.import_env_module(env_id, f"env id {env_id!r}")
    try:
        palaestra.spec(recipe.registered_id(env_id))
    except (error.UnregisteredEnv, error.DeprecatedEnv) as exc:
        raise RunError(str(exc), "run `palaestra envs` to list the ids") from None
    except error.Error as exc:  # "No registered env with id: ..." after importing the module
        where = f" (module {module!r} registers no such id)" if module else ""
        raise RunError(f"{exc}{where}", "run `palaestra envs` to list the ids") from None
