"""Two learners behind one interface: the torch learner differentiates the networks, heads and
losses with autograd; the numpy learner runs the same functions on numpy arrays and calls their
hand-written vector-Jacobian products, with a flat-buffer Adam or RMSprop (by the type of the
torch optimizer it stands in for).

An algorithm describes its networks (``Net``: the torch modules, the optimizer group it trains
in, or the net it is a target of) and hands each update an ``Objective``: the loss over ``xp``,
running nets through ``run``, and, for numpy, the loss's VJP, which sends gradients back
through ``backprop``. Several groups (an actor, twin critics, an entropy coefficient) each
take their own ``update``; ``forward`` runs a net for acting; ``polyak`` moves a target net.

Ownership (numpy learner): the learner owns the parameters and the optimizer state as flat numpy
buffers while it trains and acts. The torch modules and optimizer the user sees are brought up
to date at explicit points: ``to_torch()``, which the model calls when its ``policy``,
``optimizer`` (or DQN's ``q_net``) is read, when saving, in ``get_parameters`` and at the end
of ``learn``. Whatever is read that way may be changed by the caller (``load_state_dict``,
``set_parameters``, a loaded model file), so the learner copies the torch values back before
its next step (``from_torch``). The copies cost microseconds for the small nets it runs, and no
memory is shared behind torch's back.
"""

from __future__ import annotations

import contextlib
import itertools
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from typing import Any, Protocol

import numpy as np
import torch
from torch import nn

from palaestra.algos.learners.adam import FlatAdam, adam_unsupported, one_blas_thread
from palaestra.algos.learners.losses import polyak
from palaestra.algos.learners.mlp import MLP, NotAnMLP, describe, mlp_forward, mlp_forward_vjp
from palaestra.algos.learners.rmsprop import FlatRMSprop, rmsprop_unsupported
from palaestra.algos.learners.xp import numpy_ops, torch_ops

__all__ = ["Learner", "Net", "NumpyLearner", "Objective", "TorchLearner", "build_learner"]


@dataclass
class Net:
    """One network of an algorithm.

    ``torch_fn`` maps an observation (or input) tensor batch, or a tuple of them (a critic's
    observation and action), to the output; ``module`` holds its parameters where
    ``torch_fn`` is not a module itself (for ``polyak``); ``modules`` are
    the torch modules it consists of in order, for the numpy learner (None: not an MLP, with
    ``why``). ``group`` names the optimizer group that trains it; ``target_of`` makes it a
    frozen copy of another net, moved by ``polyak``."""

    torch_fn: Callable[[Any], Any]
    modules: list[nn.Module] | None
    group: str | None = None
    target_of: str | None = None
    why: str = ""
    module: nn.Module | None = None  # all its torch parameters (polyak), if not torch_fn


@dataclass
class Group:
    """Parameters trained together by one optimizer (in the optimizer's order)."""

    optimizer: torch.optim.Optimizer
    params: list[nn.Parameter]
    extras: dict[str, nn.Parameter] = field(default_factory=dict)  # by name, e.g. log_std


Run = Callable[[str, Any], Any]  # (net name, input batch) -> output
Backprop = Callable[..., "np.ndarray | None"]  # (net name, d/d output, input_grad=False)


class Objective(Protocol):
    """An algorithm's loss for one update, written once over ``xp``.

    ``loss(xp, run, extras, batch)`` computes ``(loss, metrics, tape)``, running nets with
    ``run(name, x)`` (each net at most once per loss; an input may be another net's output,
    as an actor's action fed to a critic). On the numpy learner, ``vjp(tape, backprop)`` then
    hands the gradient of the loss with respect to each net's output to
    ``backprop(name, g, input_grad=False)``, in reverse order of the runs, which returns
    d(loss)/d(input) when asked; it returns the gradients of the extra parameters by name."""

    def loss(
        self, xp: Any, run: Run, extras: dict[str, Any], batch: dict[str, Any]
    ) -> tuple[Any, dict[str, Any], Any]: ...

    def vjp(self, tape: Any, backprop: Backprop) -> dict[str, np.ndarray]: ...


# The flat-buffer optimizers, by the torch optimizer each stands in for, with the check of the
# options it covers: a new one is one line here.
FLAT_OPTIMIZERS: dict[type, tuple[type, Callable[[torch.optim.Optimizer], str | None]]] = {
    torch.optim.Adam: (FlatAdam, adam_unsupported),
    torch.optim.RMSprop: (FlatRMSprop, rmsprop_unsupported),
}


def flat_unsupported(optimizer: torch.optim.Optimizer) -> str | None:
    """Why no flat optimizer can stand in for ``optimizer`` (None: one can)."""
    entry = FLAT_OPTIMIZERS.get(type(optimizer))
    if entry is None:
        names = " or ".join(cls.__name__ for cls in FLAT_OPTIMIZERS)
        return f"the optimizer is {type(optimizer).__name__}, not {names}"
    return entry[1](optimizer)


class Learner:
    """What both learners share: the nets, the groups and the metrics conversion."""

    backend = ""

    def __init__(self, nets: dict[str, Net], groups: dict[str, Group], why: str) -> None:
        self.nets, self.groups, self.why = nets, groups, why

    def to_torch(self) -> None:
        """Bring the torch modules and optimizers up to date (numpy learner)."""

    @contextlib.contextmanager
    def session(self) -> Iterator[None]:
        """Around a batch of updates (numpy: matmuls on one BLAS thread)."""
        yield

    def describe(self) -> str:
        return f"{self.backend} learner ({self.why})"

    # The interface (both learners implement it; the algorithms use nothing else).
    def forward(self, name: str, x: Any) -> np.ndarray:
        """Net ``name`` on a batch of raw inputs, without gradients, as numpy."""
        raise NotImplementedError

    def extra(self, name: str) -> np.ndarray:
        """The current value of an extra parameter (e.g. ``log_std``), as numpy."""
        raise NotImplementedError

    def set_learning_rate(self, group: str, lr: float) -> None:
        raise NotImplementedError

    def update(
        self,
        group: str,
        objective: Objective,
        batch: dict[str, Any],
        max_grad_norm: float = float("inf"),
        accept: Callable[[dict[str, float]], bool] | None = None,
    ) -> tuple[dict[str, float], bool]:
        """One gradient step of ``group`` on ``objective`` over ``batch`` (numpy arrays),
        clipped to ``max_grad_norm``; skipped when ``accept(metrics)`` is False. Returns the
        metrics as floats and whether the step was taken."""
        raise NotImplementedError

    def polyak(self, target: str, tau: float) -> None:
        """Move target net ``target`` towards its online net by ``tau``."""
        raise NotImplementedError


class TorchLearner(Learner):
    """Autograd and the torch optimizers, on the model's device."""

    backend = "torch"

    def __init__(
        self,
        nets: dict[str, Net],
        groups: dict[str, Group],
        device: torch.device,
        why: str,
        joint: dict[tuple[str, ...], Callable[[Any], tuple[Any, ...]]] | None = None,
    ) -> None:
        super().__init__(nets, groups, why)
        self.device, self.joint = device, dict(joint or {})

    def tensor(self, value: Any) -> Any:
        if isinstance(value, tuple):
            return tuple(self.tensor(v) for v in value)
        if isinstance(value, dict):
            return {k: torch.as_tensor(np.asarray(v), device=self.device) for k, v in value.items()}
        return torch.as_tensor(np.asarray(value), device=self.device)

    def forward(self, name: str, x: Any) -> np.ndarray:
        with torch.no_grad():
            return self.nets[name].torch_fn(self.tensor(x)).cpu().numpy()

    def set_learning_rate(self, group: str, lr: float) -> None:
        for param_group in self.groups[group].optimizer.param_groups:
            param_group["lr"] = lr

    def extra(self, name: str) -> np.ndarray:
        for group in self.groups.values():
            if name in group.extras:
                return group.extras[name].detach().cpu().numpy()
        raise KeyError(name)

    def update(
        self,
        group: str,
        objective: Objective,
        batch: dict[str, Any],
        max_grad_norm: float = float("inf"),
        accept: Callable[[dict[str, float]], bool] | None = None,
    ) -> tuple[dict[str, float], bool]:
        """One gradient step of ``group`` on ``objective``; ``(metrics, applied)``."""
        tensors = {k: self.tensor(v) for k, v in batch.items()}
        extras = {k: v for g in self.groups.values() for k, v in g.extras.items()}
        loss, metrics, _ = objective.loss(torch_ops, self._runner(), extras, tensors)
        values = {k: torch_ops.scalar(v) for k, v in metrics.items()}
        if accept is not None and not accept(values):
            return values, False
        opt = self.groups[group].optimizer
        opt.zero_grad()
        loss.backward()
        torch.nn.utils.clip_grad_norm_(self.groups[group].params, max_grad_norm)
        opt.step()
        return values, True

    def _runner(self) -> Run:
        """``run`` for one loss: nets sharing a features extractor (``joint``) are computed
        in one pass and the partner's output kept for its own ``run`` on the same input."""
        kept: dict[tuple[str, int], Any] = {}

        def run(name: str, x: Any) -> Any:
            if (name, id(x)) in kept:
                return kept.pop((name, id(x)))
            for names, fn in self.joint.items():
                if name in names:
                    outs = fn(x)
                    kept.update({(n, id(x)): out for n, out in zip(names, outs) if n != name})
                    return outs[names.index(name)]
            net = self.nets[name]
            if net.group is None:  # a target net: no gradients
                with torch.no_grad():
                    return net.torch_fn(x)
            return net.torch_fn(x)

        return run

    def polyak(self, target: str, tau: float) -> None:
        net = self.nets[target]
        assert net.target_of is not None
        source, frozen = self.nets[net.target_of], net
        params, stats = [], []
        for n in (source, frozen):
            module = n.module if n.module is not None else n.torch_fn
            assert isinstance(module, nn.Module)
            params.append(list(module.parameters()))
            stats.append([b for name, b in module.named_buffers() if "running_" in name])
        with torch.no_grad():
            polyak(params[0], params[1], tau)
            # Batch-norm running statistics are copied whole, whatever tau (SB3's
            # polyak_update(batch_norm_stats, batch_norm_stats_target, 1.0)).
            for src, dst in zip(*stats):
                dst.copy_(src)


class NumpyLearner(Learner):
    """Hand-written VJPs and ``FlatAdam``/``FlatRMSprop`` over flat numpy buffers (see the
    module docstring)."""

    backend = "numpy"

    def __init__(self, nets: dict[str, Net], groups: dict[str, Group], why: str) -> None:
        super().__init__(nets, groups, why)
        self.mlps: dict[str, MLP] = {
            name: describe(net.modules or []) for name, net in nets.items()
        }
        # One flat buffer per optimizer group (its tensors in the group's order) and one per
        # target net; every layer and extra parameter is a view into one of them.
        self._buffers: dict[str, tuple[np.ndarray, list[nn.Parameter], list[slice]]] = {}
        self._optim: dict[str, FlatAdam | FlatRMSprop] = {}  # a flat optimizer per group
        for gname, group in groups.items():
            flat, slices = self._flat(gname, group.params)
            flat_class = FLAT_OPTIMIZERS[type(group.optimizer)][0]
            self._optim[gname] = flat_class(flat.size, len(group.params), slices)
        for name, net in nets.items():
            if net.target_of is not None:
                self._flat(f"target:{name}", list(self.mlps[name].parameters()))
        self._bind()
        self._torch_changed = True  # read everything from torch before the first use
        self._numpy_changed = False

    def _flat(self, key: str, params: list[Any]) -> tuple[np.ndarray, list[slice]]:
        bounds = np.cumsum([0] + [p.numel() for p in params]).tolist()
        slices = [slice(a, b) for a, b in itertools.pairwise(bounds)]
        flat = np.zeros(bounds[-1], dtype=np.float32)
        self._buffers[key] = (flat, list(params), slices)
        return flat, slices

    def _bind(self) -> None:
        """The per-layer and per-parameter views into the flat buffers (taken again after a
        copy: a copied view does not share memory with the copied buffer)."""
        views: dict[int, np.ndarray] = {}
        grad_views: dict[int, np.ndarray] = {}
        for key, (flat, params, slices) in self._buffers.items():
            optim = self._optim.get(key)
            for p, sl in zip(params, slices):
                views[id(p)] = flat[sl].reshape(p.shape)
                if optim is not None:
                    grad_views[id(p)] = optim.grad[sl].reshape(p.shape)
        self.layers = {
            name: [
                (views[id(lin.weight)], views[id(lin.bias)], act)
                for lin, act in zip(mlp.linears, mlp.activations)
            ]
            for name, mlp in self.mlps.items()
        }
        self.grads = {
            name: [grad_views[id(p)] for p in mlp.parameters()]
            for name, mlp in self.mlps.items()
            if self.nets[name].group is not None
        }
        groups = self.groups.values()
        self.extras = {k: views[id(p)] for g in groups for k, p in g.extras.items()}
        self.extra_grads = {k: grad_views[id(p)] for g in groups for k, p in g.extras.items()}

    def __getstate__(self) -> dict[str, Any]:
        state = self.__dict__.copy()
        for key in ("layers", "grads", "extras", "extra_grads"):
            state.pop(key, None)
        return state

    def __setstate__(self, state: dict[str, Any]) -> None:
        self.__dict__.update(state)
        self._bind()

    # -- synchronisation with the torch objects ---------------------------------------------
    def to_torch(self) -> None:
        if self._numpy_changed:
            with torch.no_grad():
                for key, (flat, params, slices) in self._buffers.items():
                    for p, sl in zip(params, slices):
                        p.copy_(torch.from_numpy(flat[sl]).view_as(p))
                    if key in self._optim:
                        self._optim[key].to_torch(self.groups[key].optimizer, params)
            self._numpy_changed = False
        self._torch_changed = True  # handed out: the caller may change it

    def _own(self) -> None:
        """Take the torch values back if they may have changed since ``to_torch``."""
        if not self._torch_changed:
            return
        for key, (flat, params, slices) in self._buffers.items():
            for p, sl in zip(params, slices):
                flat[sl] = p.detach().reshape(-1).cpu().numpy()
            if key in self._optim:
                self._optim[key].from_torch(self.groups[key].optimizer, params)
        self._torch_changed = False

    # -- the interface ------------------------------------------------------------------------
    @contextlib.contextmanager
    def session(self) -> Iterator[None]:
        with one_blas_thread():  # once per batch of updates: it costs a few µs per entry
            yield

    def forward(self, name: str, x: Any) -> np.ndarray:
        if self._torch_changed:
            self._own()
        return mlp_forward(self.layers[name], _flat_input(x))[-1]

    def set_learning_rate(self, group: str, lr: float) -> None:
        if self._torch_changed:
            self._own()
        self._optim[group].lr = lr
        self._numpy_changed = True

    def extra(self, name: str) -> np.ndarray:
        if self._torch_changed:
            self._own()
        return self.extras[name]

    def update(
        self,
        group: str,
        objective: Objective,
        batch: dict[str, Any],
        max_grad_norm: float = float("inf"),
        accept: Callable[[dict[str, float]], bool] | None = None,
    ) -> tuple[dict[str, float], bool]:
        """One gradient step of ``group`` on ``objective``; ``(metrics, applied)``."""
        if self._torch_changed:
            self._own()
        acts: dict[str, list[np.ndarray]] = {}

        def run(name: str, x: Any) -> np.ndarray:
            assert name not in acts, f"net {name!r} runs twice in one loss"
            x = _flat_input(x)
            acts[name] = mlp_forward(self.layers[name], x)
            return acts[name][-1]

        _, metrics, tape = objective.loss(numpy_ops, run, self.extras, batch)
        values = {k: float(v) for k, v in metrics.items()}
        if accept is not None and not accept(values):
            return values, False
        reached: set[str] = set()

        def backprop(name: str, g: np.ndarray, input_grad: bool = False) -> np.ndarray | None:
            trained = self.nets[name].group == group
            reached.add(name)
            g = g.astype(np.float32, copy=False)
            grads = self.grads[name] if trained else None
            return mlp_forward_vjp(self.layers[name], acts[name], g, grads, input_grad)

        extra_grads = objective.vjp(tape, backprop)
        for name, net in self.nets.items():  # trained nets the loss did not reach
            if net.group == group and name not in reached:
                for view in self.grads[name]:
                    view[...] = 0.0
        for name, view in self.extra_grads.items():
            if name in self.groups[group].extras:
                view[...] = extra_grads.get(name, 0.0)
        optim = self._optim[group]
        optim.clip_grad_norm(max_grad_norm)
        optim.step(self._buffers[group][0])
        self._numpy_changed = True
        return values, True

    def polyak(self, target: str, tau: float) -> None:
        if self._torch_changed:
            self._own()
        source = self.nets[target].target_of
        assert source is not None
        group = self.nets[source].group
        assert group is not None
        frozen = self._buffers[f"target:{target}"][0]
        online = self._buffers[group][0]
        if frozen.size == online.size:  # the group is exactly the online net
            polyak([online], [frozen], tau)
        else:
            polyak(
                [v for layer in self.layers[source] for v in layer[:2]],
                [v for layer in self.layers[target] for v in layer[:2]],
                tau,
            )
        self._numpy_changed = True


def _flat_input(x: Any) -> np.ndarray:
    """An MLP's input ``[B, in]`` float32: a batch flattened, or a tuple of batches (a
    critic's observation and action) flattened and side by side; a dict of batches (Dict
    observations) is its entries side by side in sorted key order, CombinedExtractor's order
    for the spaces the numpy learner takes (``policies._numpy_input_problem``)."""
    if type(x) is np.ndarray and x.ndim == 2 and x.dtype == np.float32 and x.shape[0]:
        # Already [B, in] float32 (vector observations, every acting step and minibatch):
        # the values the steps below give, without their three calls. (An empty batch goes
        # on to the reshape below, which refuses it as before.)
        return x
    if isinstance(x, tuple):
        parts = [_flat_input(p) for p in x]
        return np.concatenate(parts, axis=1).astype(np.float32, copy=False)
    if isinstance(x, dict):
        parts = [np.asarray(x[k]).reshape(len(x[k]), -1) for k in sorted(x)]
        return np.concatenate(parts, axis=1).astype(np.float32, copy=False)
    x = np.asarray(x)
    return x.reshape(x.shape[0], -1).astype(np.float32, copy=False)


def numpy_unsupported(nets: dict[str, Net], groups: dict[str, Group]) -> str | None:
    """Why the numpy learner cannot run these nets and groups (None: it can)."""
    for name, net in nets.items():
        if net.modules is None:
            return net.why or f"the {name} network is not an MLP"
        try:
            describe(net.modules)
        except NotAnMLP as exc:
            return f"the {name} network: {exc}"
    for group in groups.values():
        why = flat_unsupported(group.optimizer)
        if why is not None:
            return why
        in_nets = {
            id(p)
            for net in nets.values()
            if net.modules
            for m in net.modules
            for p in m.parameters()
        }
        in_nets |= {id(p) for p in group.extras.values()}
        if any(id(p) not in in_nets for p in group.params):
            return "the optimizer trains parameters outside the MLPs"
    return None


BACKENDS = ("auto", "numpy", "torch")
# "auto" leaves larger nets to torch: the numpy learner keeps its own flat copy of the
# parameters (twice the model's memory, and a copy to make at every build and load), which
# pays off only where torch's per-call overhead dominates, on small nets.
AUTO_NUMPY_MAX_PARAMETERS = 1_000_000


def build_learner(
    request: str,
    nets: dict[str, Net],
    groups: dict[str, Group],
    device: torch.device,
    joint: dict[tuple[str, ...], Callable[[Any], tuple[Any, ...]]] | None = None,
) -> Learner:
    """The learner ``request`` asks for (``"auto"``: numpy where it can run the nets on the
    CPU, else torch); ``ValueError`` naming why when numpy is asked for and cannot."""
    if request not in BACKENDS:
        raise ValueError(f"backend must be one of {BACKENDS}, got {request!r}")
    why_not = "the model is on " + str(device) if device.type != "cpu" else None
    if why_not is None:
        why_not = numpy_unsupported(nets, groups)
    if request == "numpy":
        if why_not is not None:
            raise ValueError(f"backend='numpy' cannot train this model: {why_not}")
        return NumpyLearner(nets, groups, "asked for")
    if request == "torch":
        return TorchLearner(nets, groups, device, "asked for", joint)
    if why_not is None:
        count = sum(
            p.numel() for net in nets.values() for m in net.modules or () for p in m.parameters()
        )
        if count > AUTO_NUMPY_MAX_PARAMETERS:
            why_not = f"{count} parameters, more than {AUTO_NUMPY_MAX_PARAMETERS} for 'auto'"
    if why_not is None:
        optimizers = sorted({type(g.optimizer).__name__ for g in groups.values()})
        return NumpyLearner(nets, groups, f"small MLPs with {'/'.join(optimizers)} on the CPU")
    return TorchLearner(nets, groups, device, f"numpy cannot: {why_not}", joint)


def critics(xp: Any, run: Run, names: list[str], obs: Any, actions: Any) -> list[Any]:
    """``Q(obs, actions)`` ``[B]`` of each named critic."""
    return [run(name, (obs, actions))[:, 0] for name in names]
