"""``palaestra.vector`` and ``palaestra.vec_env`` import nothing heavy, and Gymnasium's names
are where Gymnasium users look for them."""

from __future__ import annotations

import subprocess
import sys


def test_no_torch_gymnasium_or_sb3_on_import():
    code = (
        "import sys, palaestra.vector, palaestra.wrappers.vector, palaestra.vec_env;"
        "print(sorted(m for m in ('torch', 'gymnasium', 'stable_baselines3') if m in sys.modules))"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]"


def test_gymnasium_names_exist():
    import gymnasium.vector
    import gymnasium.vector.utils

    import palaestra.vector
    import palaestra.vector.utils

    for name in ("VectorEnv", "SyncVectorEnv", "AsyncVectorEnv", "AutoresetMode", "VectorWrapper"):
        assert hasattr(palaestra.vector, name) and hasattr(gymnasium.vector, name)
    for name in gymnasium.vector.utils.__all__:
        assert hasattr(palaestra.vector.utils, name), name
    assert (
        palaestra.vector.AutoresetMode("SameStep").value
        == gymnasium.vector.AutoresetMode("SameStep").value
    )
