"""The Gymnasium and SB3 names issue 16 added, imported as users write them (each statement
in a fresh namespace), and ``import palaestra`` still pulling in none of their heavy
dependencies."""

from __future__ import annotations

import subprocess
import sys

import pytest

STATEMENTS = [
    "from palaestra.wrappers.vector import HumanRendering, RecordVideo",
    "from palaestra.wrappers.vector import ArrayConversion, NumpyToTorch",
    "from palaestra.wrappers import ArrayConversion, NumpyToTorch, AddRenderObservation",
    "from palaestra.utils.play import play, PlayPlot, PlayableGame, display_arr",
    "from palaestra.utils.performance import benchmark_step, benchmark_init, benchmark_render",
    "from palaestra.utils.performance import benchmark_vector_step",
    "from palaestra.utils.step_api_compatibility import step_api_compatibility",
    "from palaestra.utils.step_api_compatibility import convert_to_done_step_api",
    "from palaestra.utils.step_api_compatibility import convert_to_terminated_truncated_step_api",
    "from palaestra.algos.buffers import ReplayBuffer, DictReplayBuffer",
    "from palaestra.algos.buffers import RolloutBuffer, DictRolloutBuffer",
    "from palaestra.algos.buffers import ReplayBufferSamples, RolloutBufferSamples",
    "from palaestra.algos.preprocessing import get_flattened_obs_dim, is_image_space",
    "from palaestra.algos.preprocessing import preprocess_obs, get_obs_shape, get_action_dim",
    "from palaestra.algos.logger import Figure, Image, Video, HParam, make_output_format",
    "from palaestra.algos.policies import ActorCriticPolicy",
    "from palaestra.algos.networks import BaseFeaturesExtractor, MlpExtractor",
]


@pytest.mark.parametrize("statement", STATEMENTS)
def test_import_as_users_write_it(statement: str) -> None:
    namespace: dict[str, object] = {}
    exec(statement, namespace)
    names = statement.split(" import ", 1)[1].split(", ")
    assert all(namespace[name] is not None for name in names)


def test_new_gymnasium_names_keep_heavy_imports_lazy() -> None:
    code = (
        "import sys\n"
        "from palaestra.wrappers.vector import HumanRendering, RecordVideo, NumpyToTorch\n"
        "from palaestra.wrappers import ArrayConversion, AddRenderObservation\n"
        "import palaestra.utils.play, palaestra.utils.performance\n"
        "print(sorted(m for m in ('torch', 'pygame', 'matplotlib', 'cv2') if m in sys.modules))"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]"
