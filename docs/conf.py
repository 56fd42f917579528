"""Sphinx configuration for palaestra's site (``make docs`` builds it into docs/_build/html).

The build is offline and strict: no intersphinx, no web fonts or CDN scripts (furo ships its own
assets; ``tests/docs/test_site.py`` checks the built HTML for external script and style URLs),
``-W --keep-going`` on the command line turns every warning into a failed build, and
``nitpicky`` makes an unresolved cross-reference a warning.
"""

from __future__ import annotations

import os
import sys
from pathlib import Path

DOCS = Path(__file__).resolve().parent
ROOT = DOCS.parent
sys.path.insert(0, str(ROOT / "src"))
sys.path.insert(0, str(DOCS / "_ext"))
# Headless rendering for the MuJoCo gallery and matplotlib figures.
os.environ.setdefault("MUJOCO_GL", "egl")
os.environ.setdefault("MPLBACKEND", "Agg")

import palaestra  # noqa: E402

project = "palaestra"
author = "the palaestra authors"
copyright = "2026, the palaestra authors"
release = getattr(palaestra, "__version__", "")

extensions = [
    "myst_parser",
    "sphinx.ext.autodoc",
    "sphinx_copybutton",
    "palaestra_exec",
    "palaestra_api",
    "palaestra_gallery",
]

source_suffix = {".md": "markdown", ".rst": "restructuredtext"}
# differences.md and known_names.md are included into pages, not pages of their own.
exclude_patterns = ["_build", "differences.md", "known_names.md", "README.md"]
myst_enable_extensions = ["colon_fence", "deflist", "attrs_inline"]
myst_heading_anchors = 3

nitpicky = True
# Types from other libraries: with no intersphinx (the build is offline) these cannot resolve;
# palaestra's own names must.
# Internal names that public docstrings and signatures mention; they are not part of the
# public reference. Each is listed by name so that any other broken reference fails the build.
nitpick_ignore = [
    ("py:class", "OwnOrInner"),
    ("py:class", "palaestra.algos.dqn.policies.QNetwork"),
    ("py:class", "palaestra.algos.qrdqn.policies.QuantileNetwork"),
    ("py:class", "palaestra.algos.common.continuous_policies.SquashedGaussianActor"),
    ("py:class", "palaestra.algos.common.continuous_policies.DeterministicActor"),
    ("py:class", "palaestra.envs.registration.EnvSpec"),
    ("py:class", "palaestra.algos.common.action_noise.ActionNoise"),
    ("py:func", "read_torch_state_dict"),
    ("py:func", "palaestra.envs.registration.make_vec"),
    ("py:mod", "palaestra.vector.engine"),
    ("py:mod", "palaestra.rendering.window"),
    ("py:attr", "return_queue"),
    ("py:attr", "length_queue"),
    ("py:attr", "time_queue"),
    ("py:func", "palaestra.utils.video.capped_cubic_video_schedule"),
]
nitpick_ignore_regex = [
    (
        r"py:.*",
        r"(numpy|np|torch|th|nn|optuna|ray|gymnasium|pandas|matplotlib|PIL|cloudpickle|collections|typing|typing_extensions|abc|os|io|pathlib|types|multiprocessing|contextlib|enum|dataclasses|logging|concurrent|tqdm|zipfile|re|functools|random|ctypes|mujoco|Box2D|ale_py)(\..*)?",
    ),
    (
        r"py:.*",
        r"(int|float|str|bool|bytes|dict|list|tuple|set|frozenset|object|type|None|callable|Callable|Any|Optional|Union|Sequence|Iterable|Iterator|Mapping|Generator|Literal|TypeVar|Self|ndarray|NDArray|PathLike|SupportsFloat|Path|ModuleType|Exception|BaseException|ValueError|TypeError|RuntimeError|ImportError|Warning|UserWarning|DeprecationWarning|slice|range|complex|bytearray|memoryview|array-like|array_like|optional|default|function|Tensor)",
    ),
    # Type variables and aliases defined in palaestra's modules are not documented objects.
    (
        r"py:.*",
        r".*\b(ObsType|ActType|RenderFrame|WrapperObsType|WrapperActType|ArrayType|T_cov|T|VecEnvObs|VecEnvStepReturn|VecEnvIndices|GymEnv|GymObs|GymStepReturn|MaybeCallback|Schedule|TensorDict|PyTorchObs|SelfBaseAlgorithm|Self\w*|EnvCreator|EnvSpec|.*Type)\b",
    ),
]

autodoc_typehints = "description"
autodoc_typehints_description_target = "documented"
autodoc_member_order = "bysource"
autodoc_inherit_docstrings = False

html_theme = "furo"
html_title = "palaestra"
html_static_path = ["_static"]
html_css_files = ["palaestra.css"]
html_show_sourcelink = False
html_theme_options = {
    "navigation_with_keys": True,
    "source_repository": "",
}
suppress_warnings: list[str] = []
