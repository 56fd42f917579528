"""The run API: what ``palaestra train``, ``eval``, ``compare`` and ``sweep`` do, as calls.

>>> from palaestra.runs import RunSpec, train_run, evaluate_run   # doctest: +SKIP
>>> spec = RunSpec.from_preset("ppo", "CartPole-v1", seed=0)      # doctest: +SKIP
>>> result = train_run(spec, "runs/ppo-cartpole")                 # doctest: +SKIP
>>> evaluate_run("runs/ppo-cartpole", episodes=10).mean_return    # doctest: +SKIP
500.0

A :class:`RunSpec` is plain JSON (``to_json``/``from_json``), so many of them can be sent to
other processes or machines: :mod:`palaestra.runs.grid` trains a list of them locally or as Ray
tasks, and :mod:`palaestra.runs.sweep` searches hyperparameters with Optuna.
"""

from palaestra.runs.errors import RunError
from palaestra.runs.evaluation import EvalResult, evaluate_run, load_model
from palaestra.runs.spec import RunSpec, resolve_spec
from palaestra.runs.training import TrainResult, open_resume, open_run, resume_run, train_run

__all__ = [
    "EvalResult",
    "RunError",
    "RunSpec",
    "TrainResult",
    "evaluate_run",
    "load_model",
    "open_resume",
    "open_run",
    "resolve_spec",
    "resume_run",
    "train_run",
]
