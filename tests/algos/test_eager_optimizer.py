"""Optimizers built without importing torch's compiler, and the same as torch's (issue 12 #7)."""

from __future__ import annotations

import copy
import os
import subprocess
import sys
from pathlib import Path

import torch

import palaestra
from palaestra.algos.common.eager_optimizer import build_optimizer


def _python(code: str) -> str:
    """Run ``code`` in a fresh interpreter importing this palaestra; its stdout."""
    src = str(Path(palaestra.__file__).resolve().parents[1])
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([src, os.environ.get("PYTHONPATH", "")])}
    proc = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, env=env, timeout=120
    )
    assert proc.returncode == 0, proc.stderr
    return proc.stdout


# Trains PPO and DQN briefly, saves and loads them; sets ``seen`` (whether torch._dynamo was
# imported after each step) and ``digest`` (the parameters' and optimizer state's bytes).
_TRAIN = """
import hashlib, sys, torch
from palaestra.algos import DQN, PPO
torch.set_num_threads(1)
seen, digest = [], {}
cases = (PPO, {"n_steps": 16, "batch_size": 16}), (DQN, {"learning_starts": 8, "train_freq": 4})
for cls, kwargs in cases:
    model = cls("MlpPolicy", "CartPole-v1", seed=0, **kwargs)
    seen.append("torch._dynamo" in sys.modules)
    model.learn(64)
    model.save(folder + "/m.zip")
    model = cls.load(folder + "/m.zip", env=model.get_env())
    seen.append("torch._dynamo" in sys.modules)
    state = model.optimizer.state_dict()["state"]
    tensors = [*model.policy.parameters(), *(t for s in state.values() for t in s.values())]
    data = b"".join(t.detach().numpy().tobytes() for t in tensors)
    digest[cls.__name__] = hashlib.sha256(data).hexdigest()
"""


def test_models_train_save_and_load_without_torch_compiler_bit_identically(
    tmp_path: Path,
) -> None:
    """No ``torch._dynamo`` import from building, training (numpy path), saving or loading;
    and the same bits as models whose optimizer torch built (compiler imported first)."""
    code = f"folder = {str(tmp_path)!r}\n{_TRAIN}\nprint(seen); print(digest)\n"
    code += (  # once the compiler is imported, torch's own wrapped methods run
        "import torch._dynamo\n"
        "model.optimizer.state_dict()\n"
        "plain = torch.optim.Optimizer.state_dict.__wrapped__\n"
        "print(getattr(plain, '__dynamo_disable', None) is not None)\n"
    )
    seen, digest, torch_path = _python(code).strip().splitlines()
    assert seen == "[False, False, False, False]"
    assert torch_path == "True"  # torch's wrapper ran: it caches its disabled function there
    import torch._dynamo  # noqa: F401  (build_optimizer now leaves everything to torch)

    here: dict = {"folder": str(tmp_path)}
    exec(_TRAIN, here)
    assert digest == str(here["digest"])


def test_a_subclass_keeps_its_own_methods_and_copies_are_plain_torch() -> None:
    class Logged(torch.optim.Adam):
        def state_dict(self) -> dict:
            return {"mine": True}

    params = [torch.nn.Parameter(torch.zeros(2))]
    assert build_optimizer(Logged, params, lr=0.1).state_dict() == {"mine": True}
    opt = build_optimizer(torch.optim.Adam, params, lr=0.1)
    assert type(opt) is torch.optim.Adam and opt.defaults["lr"] == 0.1
    clone = copy.deepcopy(opt)
    assert type(clone) is torch.optim.Adam
    assert not {"add_param_group", "zero_grad", "state_dict", "load_state_dict"} & set(vars(clone))
    assert clone.state_dict()["param_groups"] == opt.state_dict()["param_groups"]
