"""`import palaestra` loads numpy only; heavy optional libraries wait until they are used."""

import subprocess
import sys

HEAVY = ["torch", "pygame", "matplotlib", "PIL", "imageio", "ale_py", "Box2D", "gymnasium", "scipy",
         "multiprocessing", "palaestra.vector", "palaestra.utils.video", "ray", "optuna",
         "sqlalchemy"]  # fmt: skip


def test_import_loads_no_heavy_dependency() -> None:
    code = (
        "import sys, palaestra as gym\n"
        "gym.spaces.Box; gym.wrappers.TimeLimit; gym.make\n"
        f"print([m for m in {HEAVY!r} if m in sys.modules])\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]", out.stdout + out.stderr


def test_tutorial_names_exist() -> None:
    import palaestra as gym

    names = ["Env", "Wrapper", "ObservationWrapper", "RewardWrapper", "ActionWrapper", "make"]
    for name in [*names, "make_vec", "register", "registry", "spec", "pprint_registry"]:
        assert hasattr(gym, name), name
    assert gym.spaces.Discrete(3) == gym.spaces.Discrete(3)


def test_lazy_modules_resolve_on_first_use() -> None:
    import palaestra as gym

    assert gym.vector.SyncVectorEnv.__module__ == "palaestra.vector.sync_vector_env"
    assert gym.vec_env.DummyVecEnv is not None
    assert callable(gym.utils.save_video)


def test_the_run_api_and_the_cli_parser_import_neither_ray_nor_optuna() -> None:
    """Ray and Optuna wait for ``--backend ray`` and ``sweep``; torch for training."""
    code = (
        "import sys\n"
        "import palaestra.runs, palaestra.runs.grid, palaestra.runs.sweep\n"
        "from palaestra.cli import build_parser\n"
        "build_parser()\n"
        "print([m for m in ('ray', 'optuna', 'torch') if m in sys.modules])\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]", out.stdout + out.stderr
