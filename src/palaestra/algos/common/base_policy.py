"""SB3's public ``BasePolicy`` surface, shared by every palaestra policy module: ``predict``
(one observation or a batch, as ``model.predict``), ``obs_to_tensor``,
``is_vectorized_observation``, ``device``, ``set_training_mode``, ``scale_action`` /
``unscale_action``, and ``save``/``load`` of a policy alone (SB3's way to deploy without the
model).

A policy file is palaestra's no-pickle archive (``model_io``, kind ``"policy"``): the class,
its constructor arguments as JSON (classes by name, resolved as in model files), the spaces and
the ``state_dict`` as arrays. SB3 ``torch.save``s a pickle; such a file is refused unread, with
the way to convert it.
"""

from __future__ import annotations

import inspect
import os
import zipfile
from typing import Any, TypeVar

import numpy as np
import torch
from torch import nn

from palaestra import spaces
from palaestra.algos.common.model_io import (
    ModelFileError,
    decode_classes,
    encode_classes,
    read_arrays,
    read_manifest,
    resolve_path,
    write_archive,
)
from palaestra.algos.common.spaces_util import (
    is_image_space,
    is_vectorized_observation,
    refuse_reset_tuple,
    space_from_json,
    space_to_json,
)
from palaestra.algos.common.utils import get_device
from palaestra.algos.public_paths import public_ref

__all__ = ["BaseModel", "BasePolicy"]

SelfPolicy = TypeVar("SelfPolicy", bound="BasePolicy")

# Constructor arguments a policy file does not keep: SB3's lr_schedule is a function (it
# pickles it); the policies here never use it after construction.
_NOT_SAVED = ("self", "lr_schedule")


def _channels_first(obs: Any, space: spaces.Space[Any]) -> np.ndarray:
    """An image (batch) given channels-last for a channels-first space, transposed (SB3's
    ``maybe_transpose``, so a VecTransposeImage-trained policy takes env frames)."""
    obs = np.asarray(obs)
    shape = tuple(space.shape or ())
    if is_image_space(space) and obs.shape != shape and obs.shape[1:] != shape and obs.ndim >= 3:
        return np.moveaxis(obs, -1, -3)
    return obs


def _refuse_torch_pickle(path: Any) -> None:
    """A ``torch.save`` file (SB3's ``policy.save``) is a pickle: refused before any byte of
    it is unpickled, saying how to convert it."""
    source = resolve_path(path, for_write=False)
    if not isinstance(source, (str, os.PathLike)):
        return  # a file object: read_manifest refuses what is not an archive
    pickled = False
    if os.path.isfile(source):
        with open(source, "rb") as f:
            head = f.read(2)
        pickled = head[:1] == b"\x80"  # a pickle's PROTO opcode (torch's legacy format)
        if zipfile.is_zipfile(source):
            with zipfile.ZipFile(source) as zf:
                pickled = any(n.endswith("/data.pkl") for n in zf.namelist())
    if pickled:
        raise ModelFileError(
            f"{os.fspath(source)} is a PyTorch pickle (SB3's policy.save), which palaestra does "
            "not unpickle (that can run code). To convert it, load the SB3 model it belongs to "
            "with palaestra.compat.from_sb3(model_path) and save its policy with "
            "model.policy.save(path)"
        )


class BasePolicy(nn.Module):
    """What every policy module offers users (SB3's ``BasePolicy``); subclasses implement
    ``_predict(obs_tensor, deterministic)`` and keep each constructor argument as an
    attribute of the same name (or override ``_get_constructor_parameters``)."""

    # Set by each policy's constructor (typed there: a DQN policy's actions are Discrete).
    observation_space: Any
    action_space: Any
    # SAC/TD3: the networks act in [-1, 1], ``predict`` maps to the Box's bounds (SB3's).
    squash_output: bool = False
    # Frozen copies that stay in evaluation mode whatever ``set_training_mode`` says (SB3).
    _frozen: tuple[str, ...] = ()
    # ``state_dict`` prefixes an algorithm adds to the policy that its constructor does not
    # build (SAC's learned temperature): left out of a policy file.
    _not_policy_state: tuple[str, ...] = ()

    @property
    def device(self) -> torch.device:
        """The device of the first parameter (the CPU for a policy without any)."""
        for param in self.parameters():
            return param.device
        return torch.device("cpu")

    def set_training_mode(self, mode: bool) -> None:
        """Training (``True``) or evaluation mode, for dropout and batch norm; target nets
        stay in evaluation mode."""
        self.train(mode)
        for name in self._frozen:
            frozen = getattr(self, name, None)
            if isinstance(frozen, nn.Module):
                frozen.train(False)

    def is_vectorized_observation(self, observation: Any) -> bool:
        """Whether ``observation`` is a batch ``[n_env, *obs_shape]`` (SB3's shape rules)."""
        if isinstance(observation, dict) and isinstance(self.observation_space, spaces.Dict):
            observation = {
                k: _channels_first(v, self.observation_space.spaces[k])
                for k, v in observation.items()
            }
        elif not isinstance(observation, dict):
            observation = _channels_first(observation, self.observation_space)
        return is_vectorized_observation(observation, self.observation_space)

    def obs_to_tensor(self, observation: Any) -> tuple[Any, bool]:
        """``(tensor batch (a dict of them for Dict spaces) on the policy's device, whether
        the input was a batch)``; images given channels-last are transposed."""
        vectorized = self.is_vectorized_observation(observation)
        device = self.device
        if isinstance(observation, dict):
            assert isinstance(self.observation_space, spaces.Dict)  # checked just above
            tensors = {}
            for key, value in observation.items():
                sub = self.observation_space.spaces[key]
                array = _channels_first(value, sub).reshape((-1, *(sub.shape or ())))
                tensors[key] = torch.as_tensor(array, device=device)
            return tensors, vectorized
        array = _channels_first(observation, self.observation_space)
        array = array.reshape((-1, *(self.observation_space.shape or ())))
        return torch.as_tensor(array, device=device), vectorized

    def _predict(self, observation: Any, deterministic: bool = False) -> torch.Tensor:
        """Actions for a tensor batch (each policy)."""
        raise NotImplementedError

    def predict(
        self,
        observation: Any,
        state: Any = None,
        episode_start: Any = None,
        deterministic: bool = False,
    ) -> tuple[np.ndarray, Any]:
        """Actions for one observation or a batch, in evaluation mode (SB3's
        ``BasePolicy.predict``: Box actions clipped, or mapped from [-1, 1] to the bounds
        for squashing policies); ``state`` is returned as given (no recurrent policies)."""
        self.set_training_mode(False)
        refuse_reset_tuple(observation)
        obs_tensor, vectorized = self.obs_to_tensor(observation)
        with torch.no_grad():
            actions = self._predict(obs_tensor, deterministic=deterministic)
        out = actions.cpu().numpy().reshape((-1, *(self.action_space.shape or ())))
        if isinstance(self.action_space, spaces.Box):
            if self.squash_output:
                out = self.unscale_action(out)
            else:
                out = np.clip(out, self.action_space.low, self.action_space.high)
        return (out if vectorized else out.squeeze(axis=0)), state

    def _box(self) -> spaces.Box:
        if not isinstance(self.action_space, spaces.Box):
            raise TypeError(
                f"scaling actions needs a Box action space, got {self.action_space} "
                f"({type(self.action_space).__name__})"
            )
        return self.action_space

    def scale_action(self, action: np.ndarray) -> np.ndarray:
        """``[low, high]`` -> ``[-1, 1]``."""
        box = self._box()
        return 2.0 * ((action - box.low) / (box.high - box.low)) - 1.0

    def unscale_action(self, scaled_action: np.ndarray) -> np.ndarray:
        """``[-1, 1]`` -> ``[low, high]``."""
        box = self._box()
        return box.low + (0.5 * (scaled_action + 1.0) * (box.high - box.low))

    def parameters_to_vector(self) -> np.ndarray:
        """Every parameter, flattened into one vector (in ``parameters()`` order)."""
        return nn.utils.parameters_to_vector(self.parameters()).detach().cpu().numpy()

    def load_from_vector(self, vector: np.ndarray) -> None:
        """Set every parameter from a ``parameters_to_vector`` vector."""
        want = sum(p.numel() for p in self.parameters())
        if np.shape(vector) != (want,):
            raise ValueError(
                f"load_from_vector: expected a vector of {want} values, got shape "
                f"{np.shape(vector)}"
            )
        tensor = torch.as_tensor(vector, dtype=torch.float32, device=self.device)
        nn.utils.vector_to_parameters(tensor, self.parameters())

    # -- a policy file -----------------------------------------------------------------------
    def _get_constructor_parameters(self) -> dict[str, Any]:
        """The arguments that rebuild this policy: each of ``__init__``'s, read from the
        attribute of the same name (``TypeError`` naming one that has none)."""
        params = {}
        for name, param in inspect.signature(type(self).__init__).parameters.items():
            if name in _NOT_SAVED or param.kind in (param.VAR_POSITIONAL, param.VAR_KEYWORD):
                continue
            if not hasattr(self, name):
                raise TypeError(
                    f"{type(self).__name__}.save: the constructor argument {name!r} is not kept "
                    f"as an attribute; set self.{name} or override _get_constructor_parameters"
                )
            params[name] = getattr(self, name)
        return params

    def save(self, path: Any) -> None:
        """Write the policy alone (class, constructor arguments, spaces, weights) as a
        palaestra archive, atomically; ``load`` rebuilds it without any model."""
        import palaestra

        params = self._get_constructor_parameters()
        obs_space, act_space = params.pop("observation_space"), params.pop("action_space")
        meta = {
            "policy_class": encode_classes(type(self)),
            "palaestra_version": palaestra.__version__,
            "observation_space": space_to_json(obs_space),
            "action_space": space_to_json(act_space),
            "constructor": encode_classes(params),
        }
        arrays = {
            k: v.detach().cpu().numpy()
            for k, v in self.state_dict().items()
            if not k.startswith(self._not_policy_state)
        }
        write_archive(path, "policy", meta, arrays)

    @classmethod
    def load(
        cls: type[SelfPolicy],
        path: Any,
        device: torch.device | str = "auto",
        custom_objects: dict[str, Any] | None = None,
    ) -> SelfPolicy:
        """A policy written by ``save``; never unpickles. Called on ``BasePolicy`` itself, the
        file's class is used (palaestra's, or one given in ``custom_objects``); on a class,
        the file must hold that class. ``device="auto"``: the CPU (palaestra's choice for
        small nets)."""
        _refuse_torch_pickle(path)
        manifest = read_manifest(path, "policy")
        meta, name = manifest.meta, manifest.name
        custom = dict(custom_objects or {})
        try:
            saved = meta["policy_class"]
            kwargs = decode_classes(meta["constructor"], custom)
            observation_space = space_from_json(meta["observation_space"])
            action_space = space_from_json(meta["action_space"])
        except (KeyError, TypeError, ValueError) as exc:
            if isinstance(exc, ModelFileError):
                raise
            raise ModelFileError(f"{name}: malformed policy metadata ({exc!r})") from exc
        if not isinstance(saved, dict) or not isinstance(kwargs, dict):
            raise ModelFileError(f"{name}: malformed policy metadata")
        klass: Any = cls
        if cls is BasePolicy:
            klass = decode_classes(saved, custom)
        elif saved.get("__class__") != public_ref(cls):
            raise ModelFileError(
                f"{name} holds a {saved.get('__class__')!r} policy, not a {public_ref(cls)}; "
                "load it with that class (or BasePolicy.load)"
            )
        if "lr_schedule" in inspect.signature(klass.__init__).parameters:
            kwargs["lr_schedule"] = None  # not kept (see _NOT_SAVED); SB3's may be required
        policy = klass(observation_space, action_space, **kwargs)
        expected = {
            k: tuple(v.shape)
            for k, v in policy.state_dict().items()
            if not k.startswith(policy._not_policy_state)
        }

        def fits(_meta: dict[str, Any], declared: dict[str, Any]) -> None:
            got = {k: tuple(spec.shape) for k, spec in declared.items()}
            if got != expected:
                missing = sorted(set(expected) - set(got))[:3]
                extra = sorted(set(got) - set(expected))[:3]
                wrong = [k for k in expected if k in got and got[k] != expected[k]][:3]
                raise ModelFileError(
                    f"{name}: its arrays do not fit {klass.__name__} (missing {missing}, "
                    f"unexpected {extra}, wrong shape {wrong})"
                )

        arrays = read_arrays(manifest, expect=fits)
        state = {k: torch.from_numpy(np.array(v)) for k, v in arrays.items()}
        policy.load_state_dict(state, strict=not policy._not_policy_state)
        # "auto": the CPU; "cuda" without CUDA: the CPU too, as SB3's get_device
        return policy.to(get_device("cpu" if device == "auto" else device))


# SB3 splits its policy base in two (``BaseModel``: modules, device, save/load; ``BasePolicy``:
# adds predict and action scaling); palaestra's one class is both, so the names are one class.
BaseModel = BasePolicy
