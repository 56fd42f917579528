# ruff: noqa: E501  (a table: one MJCF element per line reads better than wrapped)
"""The MJCF models of palaestra's MuJoCo envs, as a table of their numbers, and what writes them.

Each model is a tree of :class:`E` (an MJCF element: its tag, attributes and children) holding
the published models' facts: bodies, joints, geoms, sizes, ranges, masses, gears, options and
colours. ``python -m palaestra.envs.mujoco._model_table`` writes them as the XML files under
``assets/`` that the envs load; ``tests/envs/mujoco/test_models.py`` checks that the committed
files are this module's output and that each compiles to the same ``MjModel`` (every numeric
array) as the model Gymnasium 1.4.0's v5 env compiles. Nothing imports this module at run time.

The cheetah's bodies carry their masses and inertias (the published file derives them from
its geoms with the compiler's deprecated ``settotalmass``, which makes MuJoCo warn into a
``MUJOCO_LOG.TXT`` in the working folder); the compiled model is the same either way.
"""

from __future__ import annotations

import math
import sys
from pathlib import Path
from typing import Any

from palaestra.utils.atomic_write import atomic_write

ASSETS = Path(__file__).parent / "assets"


class E:
    """One MJCF element: ``tag``, attributes (numbers, tuples of numbers or words) and children."""

    __slots__ = ("attrs", "kids", "tag")

    def __init__(self, tag: str, kids: list[E] | None = None, **attrs: Any) -> None:
        self.tag = tag
        self.kids = kids or []
        self.attrs = attrs


def _number(value: float | int) -> str:
    # repr: the shortest text that reads back as the same double, so the compiler sees our bits
    if isinstance(value, float) and value.is_integer() and abs(value) < 1e15:
        # "-0", not "0": the sign of a zero reaches the model (a light's direction)
        return "-0" if math.copysign(1.0, value) < 0 else str(int(value))
    return repr(value)


def _text(value: Any) -> str:
    if isinstance(value, str):
        return value
    if isinstance(value, (tuple, list)):
        return " ".join(_number(v) for v in value)
    return _number(value)


def _lines(element: E, depth: int) -> list[str]:
    pad = "  " * depth
    # name first, then the rest in alphabetical order: a stable layout to diff
    keys = sorted(element.attrs, key=lambda k: (k != "name", k))
    attrs = "".join(f' {k}="{_text(element.attrs[k])}"' for k in keys)
    if not element.kids:
        return [f"{pad}<{element.tag}{attrs}/>"]
    inner = [line for kid in element.kids for line in _lines(kid, depth + 1)]
    return [f"{pad}<{element.tag}{attrs}>", *inner, f"{pad}</{element.tag}>"]


def to_mjcf(model: E) -> str:
    """The MJCF text of ``model``."""
    header = "<!-- Written by palaestra.envs.mujoco._model_table from its table: edit that. -->"
    return "\n".join([header, *_lines(model, 0)]) + "\n"


def write_all(folder: Path = ASSETS) -> list[Path]:
    """Write every model into ``folder``; the paths written."""
    written = []
    for file_name, model in MODELS.items():
        path = folder / file_name
        with atomic_write(path, "w", encoding="utf-8") as file:
            file.write(to_mjcf(model))
        written.append(path)
    return written


def _textured_floor_assets(sky: tuple[float, ...], repeat: int) -> E:
    """The skybox, the checker floor material and the geoms' textured material."""
    return E(
        "asset",
        kids=[
            E(
                "texture",
                builtin="gradient",
                height=100,
                rgb1=sky,
                rgb2=(0, 0, 0),
                type="skybox",
                width=100,
            ),
            E(
                "texture",
                builtin="flat",
                height=1278,
                mark="cross",
                markrgb=(1, 1, 1),
                name="texgeom",
                random=0.01,
                rgb1=(0.8, 0.6, 0.4),
                rgb2=(0.8, 0.6, 0.4),
                type="cube",
                width=127,
            ),
            E(
                "texture",
                builtin="checker",
                height=100,
                name="texplane",
                rgb1=(0, 0, 0),
                rgb2=(0.8, 0.8, 0.8),
                type="2d",
                width=100,
            ),
            E(
                "material",
                name="MatPlane",
                reflectance=0.5,
                shininess=1,
                specular=1,
                texrepeat=(repeat, repeat),
                texture="texplane",
            ),
            E("material", name="geom", texture="texgeom", texuniform="true"),
        ],
    )


_TOP_LIGHT = E(
    "light",
    cutoff=100,
    diffuse=(1, 1, 1),
    dir=(-0.0, 0, -1.3),
    directional="true",
    exponent=1,
    pos=(0, 0, 1.3),
    specular=(0.1, 0.1, 0.1),
)

# fmt: off
MODELS: dict[str, E] = {
    "ant.xml": E("mujoco", model="ant", kids=[
        E("compiler", angle="degree", coordinate="local", inertiafromgeom="true"),
        E("option", integrator="RK4", timestep=0.01),
        E("custom", kids=[
            E("numeric", data=(0, 0, 0.55, 1, 0, 0, 0, 0, 1, 0, -1, 0, -1, 0, 1), name="init_qpos"),
        ]),
        E("default", kids=[
            E("joint", armature=1, damping=1, limited="true"),
            E("geom", conaffinity=0, condim=3, density=5, friction=(1, 0.5, 0.5), margin=0.01, rgba=(0.8, 0.6, 0.4, 1)),
        ]),
        _textured_floor_assets(sky=(1, 1, 1), repeat=60),
        E("worldbody", kids=[
            _TOP_LIGHT,
            E("geom", conaffinity=1, condim=3, material="MatPlane", name="floor", pos=(0, 0, 0), rgba=(0.8, 0.9, 0.8, 1), size=(40, 40, 40), type="plane"),
            E("body", name="torso", pos=(0, 0, 0.75), kids=[
                E("camera", name="track", mode="trackcom", pos=(0, -3, 0.3), xyaxes=(1, 0, 0, 0, 0, 1)),
                E("geom", name="torso_geom", pos=(0, 0, 0), size=0.25, type="sphere"),
                E("joint", armature=0, damping=0, limited="false", margin=0.01, name="root", pos=(0, 0, 0), type="free"),
                E("body", name="front_left_leg", pos=(0, 0, 0), kids=[
                    E("geom", fromto=(0, 0, 0, 0.2, 0.2, 0), name="aux_1_geom", size=0.08, type="capsule"),
                    E("body", name="aux_1", pos=(0.2, 0.2, 0), kids=[
                        E("joint", axis=(0, 0, 1), name="hip_1", pos=(0, 0, 0), range=(-30, 30), type="hinge"),
                        E("geom", fromto=(0, 0, 0, 0.2, 0.2, 0), name="left_leg_geom", size=0.08, type="capsule"),
                        E("body", pos=(0.2, 0.2, 0), kids=[
                            E("joint", axis=(-1, 1, 0), name="ankle_1", pos=(0, 0, 0), range=(30, 70), type="hinge"),
                            E("geom", fromto=(0, 0, 0, 0.4, 0.4, 0), name="left_ankle_geom", size=0.08, type="capsule"),
                        ]),
                    ]),
                ]),
                E("body", name="front_right_leg", pos=(0, 0, 0), kids=[
                    E("geom", fromto=(0, 0, 0, -0.2, 0.2, 0), name="aux_2_geom", size=0.08, type="capsule"),
                    E("body", name="aux_2", pos=(-0.2, 0.2, 0), kids=[
                        E("joint", axis=(0, 0, 1), name="hip_2", pos=(0, 0, 0), range=(-30, 30), type="hinge"),
                        E("geom", fromto=(0, 0, 0, -0.2, 0.2, 0), name="right_leg_geom", size=0.08, type="capsule"),
                        E("body", pos=(-0.2, 0.2, 0), kids=[
                            E("joint", axis=(1, 1, 0), name="ankle_2", pos=(0, 0, 0), range=(-70, -30), type="hinge"),
                            E("geom", fromto=(0, 0, 0, -0.4, 0.4, 0), name="right_ankle_geom", size=0.08, type="capsule"),
                        ]),
                    ]),
                ]),
                E("body", name="back_leg", pos=(0, 0, 0), kids=[
                    E("geom", fromto=(0, 0, 0, -0.2, -0.2, 0), name="aux_3_geom", size=0.08, type="capsule"),
                    E("body", name="aux_3", pos=(-0.2, -0.2, 0), kids=[
                        E("joint", axis=(0, 0, 1), name="hip_3", pos=(0, 0, 0), range=(-30, 30), type="hinge"),
                        E("geom", fromto=(0, 0, 0, -0.2, -0.2, 0), name="back_leg_geom", size=0.08, type="capsule"),
                        E("body", pos=(-0.2, -0.2, 0), kids=[
                            E("joint", axis=(-1, 1, 0), name="ankle_3", pos=(0, 0, 0), range=(-70, -30), type="hinge"),
                            E("geom", fromto=(0, 0, 0, -0.4, -0.4, 0), name="third_ankle_geom", size=0.08, type="capsule"),
                        ]),
                    ]),
                ]),
                E("body", name="right_back_leg", pos=(0, 0, 0), kids=[
                    E("geom", fromto=(0, 0, 0, 0.2, -0.2, 0), name="aux_4_geom", size=0.08, type="capsule"),
                    E("body", name="aux_4", pos=(0.2, -0.2, 0), kids=[
                        E("joint", axis=(0, 0, 1), name="hip_4", pos=(0, 0, 0), range=(-30, 30), type="hinge"),
                        E("geom", fromto=(0, 0, 0, 0.2, -0.2, 0), name="rightback_leg_geom", size=0.08, type="capsule"),
                        E("body", pos=(0.2, -0.2, 0), kids=[
                            E("joint", axis=(1, 1, 0), name="ankle_4", pos=(0, 0, 0), range=(30, 70), type="hinge"),
                            E("geom", fromto=(0, 0, 0, 0.4, -0.4, 0), name="fourth_ankle_geom", size=0.08, type="capsule"),
                        ]),
                    ]),
                ]),
            ]),
        ]),
        E("actuator", kids=[
            E("motor", ctrllimited="true", ctrlrange=(-1, 1), joint="hip_4", gear=150),
            E("motor", ctrllimited="true", ctrlrange=(-1, 1), joint="ankle_4", gear=150),
            E("motor", ctrllimited="true", ctrlrange=(-1, 1), joint="hip_1", gear=150),
            E("motor", ctrllimited="true", ctrlrange=(-1, 1), joint="ankle_1", gear=150),
            E("motor", ctrllimited="true", ctrlrange=(-1, 1), joint="hip_2", gear=150),
            E("motor", ctrllimited="true", ctrlrange=(-1, 1), joint="ankle_2", gear=150),
            E("motor", ctrllimited="true", ctrlrange=(-1, 1), joint="hip_3", gear=150),
            E("motor", ctrllimited="true", ctrlrange=(-1, 1), joint="ankle_3", gear=150),
        ]),
    ]),
    # The published cheetah gets its masses from its geoms scaled to a total of 14 kg by the
    # compiler's settotalmass, which MuJoCo deprecates (it warns, into MUJOCO_LOG.TXT in the
    # working folder): each body's resulting mass and inertia are written instead.
    "half_cheetah.xml": E("mujoco", model="cheetah", kids=[
        E("compiler", angle="radian", coordinate="local", inertiafromgeom="false"),
        E("default", kids=[
            E("joint", armature=0.1, damping=0.01, limited="true", solimplimit=(0, 0.8, 0.03), solreflimit=(0.02, 1), stiffness=8),
            E("geom", conaffinity=0, condim=3, contype=1, friction=(0.4, 0.1, 0.1), rgba=(0.8, 0.6, 0.4, 1), solimp=(0, 0.8, 0.01), solref=(0.02, 1)),
            E("motor", ctrllimited="true", ctrlrange=(-1, 1)),
        ]),
        E("size", nstack=300000, nuser_geom=1),
        E("option", gravity=(0, 0, -9.81), timestep=0.01),
        _textured_floor_assets(sky=(1, 1, 1), repeat=60),
        E("worldbody", kids=[
            _TOP_LIGHT,
            E("geom", conaffinity=1, condim=3, material="MatPlane", name="floor", pos=(0, 0, 0), rgba=(0.8, 0.9, 0.8, 1), size=(40, 40, 40), type="plane"),
            E("body", name="torso", pos=(0, 0, 0.7), kids=[
                E("inertial", diaginertia=(0.8971176881117434, 0.8856554522351578, 0.01796092340796636), mass=6.25020920502092, pos=(0.15238987816307403, 0.0, 0.025398313027179008), quat=(0.5224297915933479, 0.4765155956059912, 0.4765155956059912, 0.5224297915933479)),
                E("camera", name="track", mode="trackcom", pos=(0, -3, 0.3), xyaxes=(1, 0, 0, 0, 0, 1)),
                E("joint", armature=0, axis=(1, 0, 0), damping=0, limited="false", name="rootx", pos=(0, 0, 0), stiffness=0, type="slide"),
                E("joint", armature=0, axis=(0, 0, 1), damping=0, limited="false", name="rootz", pos=(0, 0, 0), stiffness=0, type="slide"),
                E("joint", armature=0, axis=(0, 1, 0), damping=0, limited="false", name="rooty", pos=(0, 0, 0), stiffness=0, type="hinge"),
                E("geom", fromto=(-0.5, 0, 0, 0.5, 0, 0), name="torso", size=0.046, type="capsule"),
                E("geom", axisangle=(0, 1, 0, 0.87), name="head", pos=(0.6, 0, 0.1), size=(0.046, 0.15), type="capsule"),
                E("body", name="bthigh", pos=(-0.5, 0, 0), kids=[
                    E("inertial", diaginertia=(0.01684433958158996, 0.01684433958158996, 0.0015760215899581589), mass=1.5435146443514645, pos=(0.1, 0.0, -0.13), quat=(-0.32328956686350335, -0.0, -0.9463000876874145, -0.0)),
                    E("joint", axis=(0, 1, 0), damping=6, name="bthigh", pos=(0, 0, 0), range=(-0.52, 1.05), stiffness=240, type="hinge"),
                    E("geom", axisangle=(0, 1, 0, -3.8), name="bthigh", pos=(0.1, 0, -0.13), size=(0.046, 0.145), type="capsule"),
                    E("body", name="bshin", pos=(0.16, 0, -0.25), kids=[
                        E("inertial", diaginertia=(0.018267419079497905, 0.018267419079497905, 0.0016225027615062756), mass=1.5874476987447697, pos=(-0.14, 0.0, -0.07), quat=(0.5276199315484069, -0.0, -0.8494805517684643, -0.0)),
                        E("joint", axis=(0, 1, 0), damping=4.5, name="bshin", pos=(0, 0, 0), range=(-0.785, 0.785), stiffness=180, type="hinge"),
                        E("geom", axisangle=(0, 1, 0, -2.03), name="bshin", pos=(-0.14, 0, -0.07), rgba=(0.9, 0.6, 0.6, 1), size=(0.046, 0.15), type="capsule"),
                        E("body", name="bfoot", pos=(-0.28, 0, -0.14), kids=[
                            E("inertial", diaginertia=(0.0063524232635983275, 0.0063524232635983275, 0.0011019136401673642), mass=1.0953974895397491, pos=(0.03, 0.0, -0.097), quat=(0.9909013312045479, -0.0, -0.1345903110073483, -0.0)),
                            E("joint", axis=(0, 1, 0), damping=3, name="bfoot", pos=(0, 0, 0), range=(-0.4, 0.785), stiffness=120, type="hinge"),
                            E("geom", axisangle=(0, 1, 0, -0.27), name="bfoot", pos=(0.03, 0, -0.097), rgba=(0.9, 0.6, 0.6, 1), size=(0.046, 0.094), type="capsule"),
                        ]),
                    ]),
                ]),
                E("body", name="fthigh", pos=(0.5, 0, 0), kids=[
                    E("inertial", diaginertia=(0.013739643347280341, 0.013739643347280341, 0.0014644667782426782), mass=1.4380753138075317, pos=(-0.07, 0.0, -0.12), quat=(0.9663899781345132, 0.0, 0.2570805518921551, 0.0)),
                    E("joint", axis=(0, 1, 0), damping=4.5, name="fthigh", pos=(0, 0, 0), range=(-1, 0.7), stiffness=180, type="hinge"),
                    E("geom", axisangle=(0, 1, 0, 0.52), name="fthigh", pos=(-0.07, 0, -0.12), size=(0.046, 0.133), type="capsule"),
                    E("body", name="fshin", pos=(-0.14, 0, -0.24), kids=[
                        E("inertial", diaginertia=(0.008222108619246861, 0.008222108619246861, 0.001213468451882845), mass=1.200836820083682, pos=(0.065, 0.0, -0.09), quat=(0.955336489125606, -0.0, -0.29552020666133955, -0.0)),
                        E("joint", axis=(0, 1, 0), damping=3, name="fshin", pos=(0, 0, 0), range=(-1.2, 0.87), stiffness=120, type="hinge"),
                        E("geom", axisangle=(0, 1, 0, -0.6), name="fshin", pos=(0.065, 0, -0.09), rgba=(0.9, 0.6, 0.6, 1), size=(0.046, 0.106), type="capsule"),
                        E("body", name="ffoot", pos=(0.13, 0, -0.18), kids=[
                            E("inertial", diaginertia=(0.003529109456066946, 0.003529109456066946, 0.0008788040167364017), mass=0.8845188284518829, pos=(0.045, 0.0, -0.07), quat=(0.955336489125606, -0.0, -0.29552020666133955, -0.0)),
                            E("joint", axis=(0, 1, 0), damping=1.5, name="ffoot", pos=(0, 0, 0), range=(-0.5, 0.5), stiffness=60, type="hinge"),
                            E("geom", axisangle=(0, 1, 0, -0.6), name="ffoot", pos=(0.045, 0, -0.07), rgba=(0.9, 0.6, 0.6, 1), size=(0.046, 0.07), type="capsule"),
                        ]),
                    ]),
                ]),
            ]),
        ]),
        E("actuator", kids=[
            E("motor", gear=120, joint="bthigh", name="bthigh"),
            E("motor", gear=90, joint="bshin", name="bshin"),
            E("motor", gear=60, joint="bfoot", name="bfoot"),
            E("motor", gear=120, joint="fthigh", name="fthigh"),
            E("motor", gear=60, joint="fshin", name="fshin"),
            E("motor", gear=30, joint="ffoot", name="ffoot"),
        ]),
    ]),
    "hopper.xml": E("mujoco", model="hopper", kids=[
        E("compiler", angle="degree", inertiafromgeom="true"),
        E("default", kids=[
            E("joint", armature=1, damping=1, limited="true"),
            E("geom", conaffinity=1, condim=1, contype=1, margin=0.001, material="geom", rgba=(0.8, 0.6, 0.4, 1), solimp=(0.8, 0.8, 0.01), solref=(0.02, 1)),
            E("motor", ctrllimited="true", ctrlrange=(-0.4, 0.4)),
        ]),
        E("option", integrator="RK4", timestep=0.002),
        E("visual", kids=[
            E("map", znear=0.02),
        ]),
        E("worldbody", kids=[
            _TOP_LIGHT,
            E("geom", conaffinity=1, condim=3, name="floor", pos=(0, 0, 0), rgba=(0.8, 0.9, 0.8, 1), size=(20, 20, 0.125), type="plane", material="MatPlane"),
            E("body", name="torso", pos=(0, 0, 1.25), kids=[
                E("camera", name="track", mode="trackcom", pos=(0, -3, -0.25), xyaxes=(1, 0, 0, 0, 0, 1)),
                E("joint", armature=0, axis=(1, 0, 0), damping=0, limited="false", name="rootx", pos=(0, 0, -1.25), stiffness=0, type="slide"),
                E("joint", armature=0, axis=(0, 0, 1), damping=0, limited="false", name="rootz", pos=(0, 0, -1.25), ref=1.25, stiffness=0, type="slide"),
                E("joint", armature=0, axis=(0, 1, 0), damping=0, limited="false", name="rooty", pos=(0, 0, 0), stiffness=0, type="hinge"),
                E("geom", friction=0.9, name="torso_geom", size=(0.05, 0.19999999999999996), type="capsule"),
                E("body", name="thigh", pos=(0, 0, -0.19999999999999996), kids=[
                    E("joint", axis=(0, -1, 0), name="thigh_joint", pos=(0, 0, 0), range=(-150, 0), type="hinge"),
                    E("geom", friction=0.9, pos=(0, 0, -0.2250000000000001), name="thigh_geom", size=(0.05, 0.22500000000000003), type="capsule"),
                    E("body", name="leg", pos=(0, 0, -0.7000000000000001), kids=[
                        E("joint", axis=(0, -1, 0), name="leg_joint", pos=(0, 0, 0.25), range=(-150, 0), type="hinge"),
                        E("geom", friction=0.9, name="leg_geom", size=(0.04, 0.25), type="capsule"),
                        E("body", name="foot", pos=(0.13, 0, -0.35), kids=[
                            E("joint", axis=(0, -1, 0), name="foot_joint", pos=(-0.13, 0, 0.1), range=(-45, 45), type="hinge"),
                            E("geom", friction=2, pos=(-0.065, 0, 0.1), quat=(0.7071067811865476, 0, -0.7071067811865475, 0), name="foot_geom", size=(0.06, 0.195), type="capsule"),
                        ]),
                    ]),
                ]),
            ]),
        ]),
        E("actuator", kids=[
            E("motor", ctrllimited="true", ctrlrange=(-1, 1), gear=200, joint="thigh_joint"),
            E("motor", ctrllimited="true", ctrlrange=(-1, 1), gear=200, joint="leg_joint"),
            E("motor", ctrllimited="true", ctrlrange=(-1, 1), gear=200, joint="foot_joint"),
        ]),
        _textured_floor_assets(sky=(0.4, 0.5, 0.6), repeat=60),
    ]),
    "humanoid.xml": E("mujoco", model="humanoid", kids=[
        E("compiler", angle="degree", inertiafromgeom="true"),
        E("default", kids=[
            E("joint", armature=1, damping=1, limited="true"),
            E("geom", conaffinity=1, condim=1, contype=1, margin=0.001, material="geom", rgba=(0.8, 0.6, 0.4, 1)),
            E("motor", ctrllimited="true", ctrlrange=(-0.4, 0.4)),
        ]),
        E("option", integrator="RK4", iterations=50, solver="PGS", timestep=0.003),
        E("size", nkey=5, nuser_geom=1),
        E("visual", kids=[
            E("map", fogend=5, fogstart=3),
        ]),
        _textured_floor_assets(sky=(0.4, 0.5, 0.6), repeat=60),
        E("worldbody", kids=[
            _TOP_LIGHT,
            E("geom", condim=3, friction=(1, 0.1, 0.1), material="MatPlane", name="floor", pos=(0, 0, 0), rgba=(0.8, 0.9, 0.8, 1), size=(20, 20, 0.125), type="plane"),
            E("body", name="torso", pos=(0, 0, 1.4), kids=[
                E("camera", name="track", mode="trackcom", pos=(0, -4, 0), xyaxes=(1, 0, 0, 0, 0, 1)),
                E("joint", armature=0, damping=0, limited="false", name="root", pos=(0, 0, 0), stiffness=0, type="free"),
                E("geom", fromto=(0, -0.07, 0, 0, 0.07, 0), name="torso1", size=0.07, type="capsule"),
                E("geom", name="head", pos=(0, 0, 0.19), size=0.09, type="sphere", user=258),
                E("geom", fromto=(-0.01, -0.06, -0.12, -0.01, 0.06, -0.12), name="uwaist", size=0.06, type="capsule"),
                E("body", name="lwaist", pos=(-0.01, 0, -0.26), quat=(1, 0, -0.002, 0), kids=[
                    E("geom", fromto=(0, -0.06, 0, 0, 0.06, 0), name="lwaist", size=0.06, type="capsule"),
                    E("joint", armature=0.02, axis=(0, 0, 1), damping=5, name="abdomen_z", pos=(0, 0, 0.065), range=(-45, 45), stiffness=20, type="hinge"),
                    E("joint", armature=0.02, axis=(0, 1, 0), damping=5, name="abdomen_y", pos=(0, 0, 0.065), range=(-75, 30), stiffness=10, type="hinge"),
                    E("body", name="pelvis", pos=(0, 0, -0.165), quat=(1, 0, -0.002, 0), kids=[
                        E("joint", armature=0.02, axis=(1, 0, 0), damping=5, name="abdomen_x", pos=(0, 0, 0.1), range=(-35, 35), stiffness=10, type="hinge"),
                        E("geom", fromto=(-0.02, -0.07, 0, -0.02, 0.07, 0), name="butt", size=0.09, type="capsule"),
                        E("body", name="right_thigh", pos=(0, -0.1, -0.04), kids=[
                            E("joint", armature=0.01, axis=(1, 0, 0), damping=5, name="right_hip_x", pos=(0, 0, 0), range=(-25, 5), stiffness=10, type="hinge"),
                            E("joint", armature=0.01, axis=(0, 0, 1), damping=5, name="right_hip_z", pos=(0, 0, 0), range=(-60, 35), stiffness=10, type="hinge"),
                            E("joint", armature=0.008, axis=(0, 1, 0), damping=5, name="right_hip_y", pos=(0, 0, 0), range=(-110, 20), stiffness=20, type="hinge"),
                            E("geom", fromto=(0, 0, 0, 0, 0.01, -0.34), name="right_thigh1", size=0.06, type="capsule"),
                            E("body", name="right_shin", pos=(0, 0.01, -0.403), kids=[
                                E("joint", armature=0.006, axis=(0, -1, 0), name="right_knee", pos=(0, 0, 0.02), range=(-160, -2), type="hinge"),
                                E("geom", fromto=(0, 0, 0, 0, 0, -0.3), name="right_shin1", size=0.049, type="capsule"),
                                E("body", name="right_foot", pos=(0, 0, -0.45), kids=[
                                    E("geom", name="right_foot", pos=(0, 0, 0.1), size=0.075, type="sphere", user=0),
                                ]),
                            ]),
                        ]),
                        E("body", name="left_thigh", pos=(0, 0.1, -0.04), kids=[
                            E("joint", armature=0.01, axis=(-1, 0, 0), damping=5, name="left_hip_x", pos=(0, 0, 0), range=(-25, 5), stiffness=10, type="hinge"),
                            E("joint", armature=0.01, axis=(0, 0, -1), damping=5, name="left_hip_z", pos=(0, 0, 0), range=(-60, 35), stiffness=10, type="hinge"),
                            E("joint", armature=0.01, axis=(0, 1, 0), damping=5, name="left_hip_y", pos=(0, 0, 0), range=(-110, 20), stiffness=20, type="hinge"),
                            E("geom", fromto=(0, 0, 0, 0, -0.01, -0.34), name="left_thigh1", size=0.06, type="capsule"),
                            E("body", name="left_shin", pos=(0, -0.01, -0.403), kids=[
                                E("joint", armature=0.006, axis=(0, -1, 0), name="left_knee", pos=(0, 0, 0.02), range=(-160, -2), stiffness=1, type="hinge"),
                                E("geom", fromto=(0, 0, 0, 0, 0, -0.3), name="left_shin1", size=0.049, type="capsule"),
                                E("body", name="left_foot", pos=(0, 0, -0.45), kids=[
                                    E("geom", name="left_foot", type="sphere", size=0.075, pos=(0, 0, 0.1), user=0),
                                ]),
                            ]),
                        ]),
                    ]),
                ]),
                E("body", name="right_upper_arm", pos=(0, -0.17, 0.06), kids=[
                    E("joint", armature=0.0068, axis=(2, 1, 1), name="right_shoulder1", pos=(0, 0, 0), range=(-85, 60), stiffness=1, type="hinge"),
                    E("joint", armature=0.0051, axis=(0, -1, 1), name="right_shoulder2", pos=(0, 0, 0), range=(-85, 60), stiffness=1, type="hinge"),
                    E("geom", fromto=(0, 0, 0, 0.16, -0.16, -0.16), name="right_uarm1", size=(0.04, 0.16), type="capsule"),
                    E("body", name="right_lower_arm", pos=(0.18, -0.18, -0.18), kids=[
                        E("joint", armature=0.0028, axis=(0, -1, 1), name="right_elbow", pos=(0, 0, 0), range=(-90, 50), stiffness=0, type="hinge"),
                        E("geom", fromto=(0.01, 0.01, 0.01, 0.17, 0.17, 0.17), name="right_larm", size=0.031, type="capsule"),
                        E("geom", name="right_hand", pos=(0.18, 0.18, 0.18), size=0.04, type="sphere"),
                        E("camera", pos=(0, 0, 0)),
                    ]),
                ]),
                E("body", name="left_upper_arm", pos=(0, 0.17, 0.06), kids=[
                    E("joint", armature=0.0068, axis=(2, -1, 1), name="left_shoulder1", pos=(0, 0, 0), range=(-60, 85), stiffness=1, type="hinge"),
                    E("joint", armature=0.0051, axis=(0, 1, 1), name="left_shoulder2", pos=(0, 0, 0), range=(-60, 85), stiffness=1, type="hinge"),
                    E("geom", fromto=(0, 0, 0, 0.16, 0.16, -0.16), name="left_uarm1", size=(0.04, 0.16), type="capsule"),
                    E("body", name="left_lower_arm", pos=(0.18, 0.18, -0.18), kids=[
                        E("joint", armature=0.0028, axis=(0, -1, -1), name="left_elbow", pos=(0, 0, 0), range=(-90, 50), stiffness=0, type="hinge"),
                        E("geom", fromto=(0.01, -0.01, 0.01, 0.17, -0.17, 0.17), name="left_larm", size=0.031, type="capsule"),
                        E("geom", name="left_hand", pos=(0.18, -0.18, 0.18), size=0.04, type="sphere"),
                    ]),
                ]),
            ]),
        ]),
        E("tendon", kids=[
            E("fixed", name="left_hipknee", kids=[
                E("joint", coef=-1, joint="left_hip_y"),
                E("joint", coef=1, joint="left_knee"),
            ]),
            E("fixed", name="right_hipknee", kids=[
                E("joint", coef=-1, joint="right_hip_y"),
                E("joint", coef=1, joint="right_knee"),
            ]),
        ]),
        E("actuator", kids=[
            E("motor", gear=100, joint="abdomen_y", name="abdomen_y"),
            E("motor", gear=100, joint="abdomen_z", name="abdomen_z"),
            E("motor", gear=100, joint="abdomen_x", name="abdomen_x"),
            E("motor", gear=100, joint="right_hip_x", name="right_hip_x"),
            E("motor", gear=100, joint="right_hip_z", name="right_hip_z"),
            E("motor", gear=300, joint="right_hip_y", name="right_hip_y"),
            E("motor", gear=200, joint="right_knee", name="right_knee"),
            E("motor", gear=100, joint="left_hip_x", name="left_hip_x"),
            E("motor", gear=100, joint="left_hip_z", name="left_hip_z"),
            E("motor", gear=300, joint="left_hip_y", name="left_hip_y"),
            E("motor", gear=200, joint="left_knee", name="left_knee"),
            E("motor", gear=25, joint="right_shoulder1", name="right_shoulder1"),
            E("motor", gear=25, joint="right_shoulder2", name="right_shoulder2"),
            E("motor", gear=25, joint="right_elbow", name="right_elbow"),
            E("motor", gear=25, joint="left_shoulder1", name="left_shoulder1"),
            E("motor", gear=25, joint="left_shoulder2", name="left_shoulder2"),
            E("motor", gear=25, joint="left_elbow", name="left_elbow"),
        ]),
    ]),
    "humanoidstandup.xml": E("mujoco", model="humanoidstandup", kids=[
        E("compiler", angle="degree", inertiafromgeom="true"),
        E("default", kids=[
            E("joint", armature=1, damping=1, limited="true"),
            E("geom", conaffinity=1, condim=1, contype=1, margin=0.001, material="geom", rgba=(0.8, 0.6, 0.4, 1)),
            E("motor", ctrllimited="true", ctrlrange=(-0.4, 0.4)),
        ]),
        E("option", integrator="RK4", iterations=50, solver="PGS", timestep=0.003),
        E("size", nkey=5, nuser_geom=1),
        E("visual", kids=[
            E("map", fogend=5, fogstart=3),
        ]),
        _textured_floor_assets(sky=(0.4, 0.5, 0.6), repeat=60),
        E("worldbody", kids=[
            _TOP_LIGHT,
            E("geom", condim=3, friction=(1, 0.1, 0.1), material="MatPlane", name="floor", pos=(0, 0, 0), rgba=(0.8, 0.9, 0.8, 1), size=(20, 20, 0.125), type="plane"),
            E("body", name="torso", pos=(0, 0, 0.105), kids=[
                E("camera", name="track", mode="trackcom", pos=(0, -3, 0.5), xyaxes=(1, 0, 0, 0, 0, 1)),
                E("joint", armature=0, damping=0, limited="false", name="root", pos=(0, 0, 0), stiffness=0, type="free"),
                E("geom", fromto=(0, -0.07, 0, 0, 0.07, 0), name="torso1", size=0.07, type="capsule"),
                E("geom", name="head", pos=(-0.15, 0, 0), size=0.09, type="sphere", user=258),
                E("geom", fromto=(0.11, -0.06, 0, 0.11, 0.06, 0), name="uwaist", size=0.06, type="capsule"),
                E("body", name="lwaist", pos=(0.21, 0, 0), quat=(1, 0, -0.002, 0), kids=[
                    E("geom", fromto=(0, -0.06, 0, 0, 0.06, 0), name="lwaist", size=0.06, type="capsule"),
                    E("joint", armature=0.02, axis=(0, 0, 1), damping=5, name="abdomen_z", pos=(0, 0, 0.065), range=(-45, 45), stiffness=20, type="hinge"),
                    E("joint", armature=0.02, axis=(0, 1, 0), damping=5, name="abdomen_y", pos=(0, 0, 0.065), range=(-75, 30), stiffness=10, type="hinge"),
                    E("body", name="pelvis", pos=(0.165, 0, 0), quat=(1, 0, -0.002, 0), kids=[
                        E("joint", armature=0.02, axis=(1, 0, 0), damping=5, name="abdomen_x", pos=(0, 0, 0.1), range=(-35, 35), stiffness=10, type="hinge"),
                        E("geom", fromto=(-0.02, -0.07, 0, -0.02, 0.07, 0), name="butt", size=0.09, type="capsule"),
                        E("body", name="right_thigh", pos=(0, -0.1, 0), kids=[
                            E("joint", armature=0.01, axis=(1, 0, 0), damping=5, name="right_hip_x", pos=(0, 0, 0), range=(-25, 5), stiffness=10, type="hinge"),
                            E("joint", armature=0.01, axis=(0, 0, 1), damping=5, name="right_hip_z", pos=(0, 0, 0), range=(-60, 35), stiffness=10, type="hinge"),
                            E("joint", armature=0.008, axis=(0, 1, 0), damping=5, name="right_hip_y", pos=(0, 0, 0), range=(-110, 20), stiffness=20, type="hinge"),
                            E("geom", fromto=(0, 0, 0, 0.34, 0.01, 0), name="right_thigh1", size=0.06, type="capsule"),
                            E("body", name="right_shin", pos=(0.403, 0.01, 0), kids=[
                                E("joint", armature=0.006, axis=(0, -1, 0), name="right_knee", pos=(0, 0, 0.02), range=(-160, -2), type="hinge"),
                                E("geom", fromto=(0, 0, 0, 0.3, 0, 0), name="right_shin1", size=0.049, type="capsule"),
                                E("body", name="right_foot", pos=(0.35, 0, -0.1), kids=[
                                    E("geom", name="right_foot", pos=(0, 0, 0.1), size=0.075, type="sphere", user=0),
                                ]),
                            ]),
                        ]),
                        E("body", name="left_thigh", pos=(0, 0.1, 0), kids=[
                            E("joint", armature=0.01, axis=(-1, 0, 0), damping=5, name="left_hip_x", pos=(0, 0, 0), range=(-25, 5), stiffness=10, type="hinge"),
                            E("joint", armature=0.01, axis=(0, 0, -1), damping=5, name="left_hip_z", pos=(0, 0, 0), range=(-60, 35), stiffness=10, type="hinge"),
                            E("joint", armature=0.01, axis=(0, 1, 0), damping=5, name="left_hip_y", pos=(0, 0, 0), range=(-120, 20), stiffness=20, type="hinge"),
                            E("geom", fromto=(0, 0, 0, 0.34, -0.01, 0), name="left_thigh1", size=0.06, type="capsule"),
                            E("body", name="left_shin", pos=(0.403, -0.01, 0), kids=[
                                E("joint", armature=0.006, axis=(0, -1, 0), name="left_knee", pos=(0, 0, 0.02), range=(-160, -2), stiffness=1, type="hinge"),
                                E("geom", fromto=(0, 0, 0, 0.3, 0, 0), name="left_shin1", size=0.049, type="capsule"),
                                E("body", name="left_foot", pos=(0.35, 0, -0.1), kids=[
                                    E("geom", name="left_foot", type="sphere", size=0.075, pos=(0, 0, 0.1), user=0),
                                ]),
                            ]),
                        ]),
                    ]),
                ]),
                E("body", name="right_upper_arm", pos=(0, -0.17, 0.06), kids=[
                    E("joint", armature=0.0068, axis=(2, 1, 1), name="right_shoulder1", pos=(0, 0, 0), range=(-85, 60), stiffness=1, type="hinge"),
                    E("joint", armature=0.0051, axis=(0, -1, 1), name="right_shoulder2", pos=(0, 0, 0), range=(-85, 60), stiffness=1, type="hinge"),
                    E("geom", fromto=(0, 0, 0, 0.16, -0.16, -0.16), name="right_uarm1", size=(0.04, 0.16), type="capsule"),
                    E("body", name="right_lower_arm", pos=(0.18, -0.18, -0.18), kids=[
                        E("joint", armature=0.0028, axis=(0, -1, 1), name="right_elbow", pos=(0, 0, 0), range=(-90, 50), stiffness=0, type="hinge"),
                        E("geom", fromto=(0.01, 0.01, 0.01, 0.17, 0.17, 0.17), name="right_larm", size=0.031, type="capsule"),
                        E("geom", name="right_hand", pos=(0.18, 0.18, 0.18), size=0.04, type="sphere"),
                        E("camera", pos=(0, 0, 0)),
                    ]),
                ]),
                E("body", name="left_upper_arm", pos=(0, 0.17, 0.06), kids=[
                    E("joint", armature=0.0068, axis=(2, -1, 1), name="left_shoulder1", pos=(0, 0, 0), range=(-60, 85), stiffness=1, type="hinge"),
                    E("joint", armature=0.0051, axis=(0, 1, 1), name="left_shoulder2", pos=(0, 0, 0), range=(-60, 85), stiffness=1, type="hinge"),
                    E("geom", fromto=(0, 0, 0, 0.16, 0.16, -0.16), name="left_uarm1", size=(0.04, 0.16), type="capsule"),
                    E("body", name="left_lower_arm", pos=(0.18, 0.18, -0.18), kids=[
                        E("joint", armature=0.0028, axis=(0, -1, -1), name="left_elbow", pos=(0, 0, 0), range=(-90, 50), stiffness=0, type="hinge"),
                        E("geom", fromto=(0.01, -0.01, 0.01, 0.17, -0.17, 0.17), name="left_larm", size=0.031, type="capsule"),
                        E("geom", name="left_hand", pos=(0.18, -0.18, 0.18), size=0.04, type="sphere"),
                    ]),
                ]),
            ]),
        ]),
        E("tendon", kids=[
            E("fixed", name="left_hipknee", kids=[
                E("joint", coef=-1, joint="left_hip_y"),
                E("joint", coef=1, joint="left_knee"),
            ]),
            E("fixed", name="right_hipknee", kids=[
                E("joint", coef=-1, joint="right_hip_y"),
                E("joint", coef=1, joint="right_knee"),
            ]),
        ]),
        E("actuator", kids=[
            E("motor", gear=100, joint="abdomen_y", name="abdomen_y"),
            E("motor", gear=100, joint="abdomen_z", name="abdomen_z"),
            E("motor", gear=100, joint="abdomen_x", name="abdomen_x"),
            E("motor", gear=100, joint="right_hip_x", name="right_hip_x"),
            E("motor", gear=100, joint="right_hip_z", name="right_hip_z"),
            E("motor", gear=300, joint="right_hip_y", name="right_hip_y"),
            E("motor", gear=200, joint="right_knee", name="right_knee"),
            E("motor", gear=100, joint="left_hip_x", name="left_hip_x"),
            E("motor", gear=100, joint="left_hip_z", name="left_hip_z"),
            E("motor", gear=300, joint="left_hip_y", name="left_hip_y"),
            E("motor", gear=200, joint="left_knee", name="left_knee"),
            E("motor", gear=25, joint="right_shoulder1", name="right_shoulder1"),
            E("motor", gear=25, joint="right_shoulder2", name="right_shoulder2"),
            E("motor", gear=25, joint="right_elbow", name="right_elbow"),
            E("motor", gear=25, joint="left_shoulder1", name="left_shoulder1"),
            E("motor", gear=25, joint="left_shoulder2", name="left_shoulder2"),
            E("motor", gear=25, joint="left_elbow", name="left_elbow"),
        ]),
    ]),
    "inverted_double_pendulum.xml": E("mujoco", model="cartpole", kids=[
        E("compiler", coordinate="local", inertiafromgeom="true"),
        E("custom", kids=[
            E("numeric", data=2, name="frame_skip"),
        ]),
        E("default", kids=[
            E("joint", damping=0.05),
            E("geom", contype=0, friction=(1, 0.1, 0.1), rgba=(0.7, 0.7, 0, 1)),
        ]),
        E("option", gravity=(1e-05, 0, -9.81), integrator="RK4", timestep=0.01),
        E("size", nstack=3000),
        E("worldbody", kids=[
            E("geom", name="floor", pos=(0, 0, -3), rgba=(0.8, 0.9, 0.8, 1), size=(40, 40, 40), type="plane"),
            E("geom", name="rail", pos=(0, 0, 0), quat=(0.707, 0, 0.707, 0), rgba=(0.3, 0.3, 0.7, 1), size=(0.02, 1), type="capsule"),
            E("body", name="cart", pos=(0, 0, 0), kids=[
                E("joint", axis=(1, 0, 0), limited="true", margin=0.01, name="slider", pos=(0, 0, 0), range=(-1, 1), type="slide"),
                E("geom", name="cart", pos=(0, 0, 0), quat=(0.707, 0, 0.707, 0), size=(0.1, 0.1), type="capsule"),
                E("body", name="pole", pos=(0, 0, 0), kids=[
                    E("joint", axis=(0, 1, 0), name="hinge", pos=(0, 0, 0), type="hinge"),
                    E("geom", fromto=(0, 0, 0, 0, 0, 0.6), name="cpole", rgba=(0, 0.7, 0.7, 1), size=(0.045, 0.3), type="capsule"),
                    E("body", name="pole2", pos=(0, 0, 0.6), kids=[
                        E("joint", axis=(0, 1, 0), name="hinge2", pos=(0, 0, 0), type="hinge"),
                        E("geom", fromto=(0, 0, 0, 0, 0, 0.6), name="cpole2", rgba=(0, 0.7, 0.7, 1), size=(0.045, 0.3), type="capsule"),
                        E("site", name="tip", pos=(0, 0, 0.6), size=(0.01, 0.01)),
                    ]),
                ]),
            ]),
        ]),
        E("actuator", kids=[
            E("motor", ctrllimited="true", ctrlrange=(-1, 1), gear=500, joint="slider", name="slide"),
        ]),
    ]),
    "inverted_pendulum.xml": E("mujoco", model="inverted pendulum", kids=[
        E("compiler", inertiafromgeom="true"),
        E("default", kids=[
            E("joint", armature=0, damping=1, limited="true"),
            E("geom", contype=0, friction=(1, 0.1, 0.1), rgba=(0.7, 0.7, 0, 1)),
            E("tendon"),
            E("motor", ctrlrange=(-3, 3)),
        ]),
        E("option", gravity=(0, 0, -9.81), integrator="RK4", timestep=0.02),
        E("size", nstack=3000),
        E("worldbody", kids=[
            E("geom", name="rail", pos=(0, 0, 0), quat=(0.707, 0, 0.707, 0), rgba=(0.3, 0.3, 0.7, 1), size=(0.02, 1), type="capsule"),
            E("body", name="cart", pos=(0, 0, 0), kids=[
                E("joint", axis=(1, 0, 0), limited="true", name="slider", pos=(0, 0, 0), range=(-1, 1), type="slide"),
                E("geom", name="cart", pos=(0, 0, 0), quat=(0.707, 0, 0.707, 0), size=(0.1, 0.1), type="capsule"),
                E("body", name="pole", pos=(0, 0, 0), kids=[
                    E("joint", axis=(0, 1, 0), name="hinge", pos=(0, 0, 0), range=(-90, 90), type="hinge"),
                    E("geom", fromto=(0, 0, 0, 0.001, 0, 0.6), name="cpole", rgba=(0, 0.7, 0.7, 1), size=(0.049, 0.3), type="capsule"),
                ]),
            ]),
        ]),
        E("actuator", kids=[
            E("motor", ctrllimited="true", ctrlrange=(-3, 3), gear=100, joint="slider", name="slide"),
        ]),
    ]),
    "pusher_v5.xml": E("mujoco", model="arm3d", kids=[
        E("compiler", inertiafromgeom="true", angle="radian", coordinate="local"),
        E("option", timestep=0.01, gravity=(0, 0, 0), iterations=20, integrator="Euler"),
        E("default", kids=[
            E("joint", armature=0.04, damping=1, limited="true"),
            E("geom", friction=(0.8, 0.1, 0.1), density=300, margin=0.002, condim=1, contype=0, conaffinity=0),
        ]),
        E("worldbody", kids=[
            E("light", diffuse=(0.5, 0.5, 0.5), pos=(0, 0, 3), dir=(0, 0, -1)),
            E("geom", name="table", type="plane", pos=(0, 0.5, -0.325), size=(1, 1, 0.1), contype=1, conaffinity=1),
            E("body", name="r_shoulder_pan_link", pos=(0, -0.6, 0), kids=[
                E("geom", name="e1", type="sphere", rgba=(0.6, 0.6, 0.6, 1), pos=(-0.06, 0.05, 0.2), size=0.05),
                E("geom", name="e2", type="sphere", rgba=(0.6, 0.6, 0.6, 1), pos=(0.06, 0.05, 0.2), size=0.05),
                E("geom", name="e1p", type="sphere", rgba=(0.1, 0.1, 0.1, 1), pos=(-0.06, 0.09, 0.2), size=0.03),
                E("geom", name="e2p", type="sphere", rgba=(0.1, 0.1, 0.1, 1), pos=(0.06, 0.09, 0.2), size=0.03),
                E("geom", name="sp", type="capsule", fromto=(0, 0, -0.4, 0, 0, 0.2), size=0.1),
                E("joint", name="r_shoulder_pan_joint", type="hinge", pos=(0, 0, 0), axis=(0, 0, 1), range=(-2.2854, 1.714602), damping=1),
                E("body", name="r_shoulder_lift_link", pos=(0.1, 0, 0), kids=[
                    E("geom", name="sl", type="capsule", fromto=(0, -0.1, 0, 0, 0.1, 0), size=0.1),
                    E("joint", name="r_shoulder_lift_joint", type="hinge", pos=(0, 0, 0), axis=(0, 1, 0), range=(-0.5236, 1.3963), damping=1),
                    E("body", name="r_upper_arm_roll_link", pos=(0, 0, 0), kids=[
                        E("geom", name="uar", type="capsule", fromto=(-0.1, 0, 0, 0.1, 0, 0), size=0.02),
                        E("joint", name="r_upper_arm_roll_joint", type="hinge", pos=(0, 0, 0), axis=(1, 0, 0), range=(-1.5, 1.7), damping=0.1),
                        E("body", name="r_upper_arm_link", pos=(0, 0, 0), kids=[
                            E("geom", name="ua", type="capsule", fromto=(0, 0, 0, 0.4, 0, 0), size=0.06),
                            E("body", name="r_elbow_flex_link", pos=(0.4, 0, 0), kids=[
                                E("geom", name="ef", type="capsule", fromto=(0, -0.02, 0, 0, 0.02, 0), size=0.06),
                                E("joint", name="r_elbow_flex_joint", type="hinge", pos=(0, 0, 0), axis=(0, 1, 0), range=(-2.3213, 0), damping=0.1),
                                E("body", name="r_forearm_roll_link", pos=(0, 0, 0), kids=[
                                    E("geom", name="fr", type="capsule", fromto=(-0.1, 0, 0, 0.1, 0, 0), size=0.02),
                                    E("joint", name="r_forearm_roll_joint", type="hinge", limited="true", pos=(0, 0, 0), axis=(1, 0, 0), damping=0.1, range=(-1.5, 1.5)),
                                    E("body", name="r_forearm_link", pos=(0, 0, 0), kids=[
                                        E("geom", name="fa", type="capsule", fromto=(0, 0, 0, 0.291, 0, 0), size=0.05),
                                        E("body", name="r_wrist_flex_link", pos=(0.321, 0, 0), kids=[
                                            E("geom", name="wf", type="capsule", fromto=(0, -0.02, 0, 0, 0.02, 0), size=0.01),
                                            E("joint", name="r_wrist_flex_joint", type="hinge", pos=(0, 0, 0), axis=(0, 1, 0), range=(-1.094, 0), damping=0.1),
                                            E("body", name="r_wrist_roll_link", pos=(0, 0, 0), kids=[
                                                E("joint", name="r_wrist_roll_joint", type="hinge", pos=(0, 0, 0), limited="true", axis=(1, 0, 0), damping=0.1, range=(-1.5, 1.5)),
                                                E("body", name="tips_arm", pos=(0, 0, 0), kids=[
                                                    E("geom", name="tip_arml", type="sphere", pos=(0.1, -0.1, 0), size=0.01),
                                                    E("geom", name="tip_armr", type="sphere", pos=(0.1, 0.1, 0), size=0.01),
                                                ]),
                                                E("geom", type="capsule", fromto=(0, -0.1, 0, 0, 0.1, 0), size=0.02, contype=1, conaffinity=1),
                                                E("geom", type="capsule", fromto=(0, -0.1, 0, 0.1, -0.1, 0), size=0.02, contype=1, conaffinity=1),
                                                E("geom", type="capsule", fromto=(0, 0.1, 0, 0.1, 0.1, 0), size=0.02, contype=1, conaffinity=1),
                                            ]),
                                        ]),
                                    ]),
                                ]),
                            ]),
                        ]),
                    ]),
                ]),
            ]),
            E("body", name="object", pos=(0.45, -0.05, -0.275), kids=[
                E("geom", rgba=(1, 1, 1, 1), type="cylinder", size=(0.05, 0.05, 0.05), density=0.01, contype=1, conaffinity=0),
                E("joint", name="obj_slidey", type="slide", pos=(0, 0, 0), axis=(0, 1, 0), range=(-10.3213, 10.3), damping=0.5),
                E("joint", name="obj_slidex", type="slide", pos=(0, 0, 0), axis=(1, 0, 0), range=(-10.3213, 10.3), damping=0.5),
            ]),
            E("body", name="goal", pos=(0.45, -0.05, -0.323), kids=[
                E("geom", rgba=(1, 0, 0, 1), type="cylinder", size=(0.08, 0.001, 0.1), density=1e-05, contype=0, conaffinity=0),
                E("joint", name="goal_slidey", type="slide", pos=(0, 0, 0), axis=(0, 1, 0), range=(-10.3213, 10.3), damping=0.5),
                E("joint", name="goal_slidex", type="slide", pos=(0, 0, 0), axis=(1, 0, 0), range=(-10.3213, 10.3), damping=0.5),
            ]),
        ]),
        E("actuator", kids=[
            E("motor", joint="r_shoulder_pan_joint", ctrlrange=(-2, 2), ctrllimited="true"),
            E("motor", joint="r_shoulder_lift_joint", ctrlrange=(-2, 2), ctrllimited="true"),
            E("motor", joint="r_upper_arm_roll_joint", ctrlrange=(-2, 2), ctrllimited="true"),
            E("motor", joint="r_elbow_flex_joint", ctrlrange=(-2, 2), ctrllimited="true"),
            E("motor", joint="r_forearm_roll_joint", ctrlrange=(-2, 2), ctrllimited="true"),
            E("motor", joint="r_wrist_flex_joint", ctrlrange=(-2, 2), ctrllimited="true"),
            E("motor", joint="r_wrist_roll_joint", ctrlrange=(-2, 2), ctrllimited="true"),
        ]),
    ]),
    "reacher.xml": E("mujoco", model="reacher", kids=[
        E("compiler", angle="radian", inertiafromgeom="true"),
        E("default", kids=[
            E("joint", armature=1, damping=1, limited="true"),
            E("geom", contype=0, friction=(1, 0.1, 0.1), rgba=(0.7, 0.7, 0, 1)),
        ]),
        E("option", gravity=(0, 0, -9.81), integrator="RK4", timestep=0.01),
        E("worldbody", kids=[
            E("geom", conaffinity=0, contype=0, name="ground", pos=(0, 0, 0), rgba=(0.9, 0.9, 0.9, 1), size=(1, 1, 10), type="plane"),
            E("geom", conaffinity=0, fromto=(-0.3, -0.3, 0.01, 0.3, -0.3, 0.01), name="sideS", rgba=(0.9, 0.4, 0.6, 1), size=0.02, type="capsule"),
            E("geom", conaffinity=0, fromto=(0.3, -0.3, 0.01, 0.3, 0.3, 0.01), name="sideE", rgba=(0.9, 0.4, 0.6, 1), size=0.02, type="capsule"),
            E("geom", conaffinity=0, fromto=(-0.3, 0.3, 0.01, 0.3, 0.3, 0.01), name="sideN", rgba=(0.9, 0.4, 0.6, 1), size=0.02, type="capsule"),
            E("geom", conaffinity=0, fromto=(-0.3, -0.3, 0.01, -0.3, 0.3, 0.01), name="sideW", rgba=(0.9, 0.4, 0.6, 1), size=0.02, type="capsule"),
            E("geom", conaffinity=0, contype=0, fromto=(0, 0, 0, 0, 0, 0.02), name="root", rgba=(0.9, 0.4, 0.6, 1), size=0.011, type="cylinder"),
            E("body", name="body0", pos=(0, 0, 0.01), kids=[
                E("geom", fromto=(0, 0, 0, 0.1, 0, 0), name="link0", rgba=(0, 0.4, 0.6, 1), size=0.01, type="capsule"),
                E("joint", axis=(0, 0, 1), limited="false", name="joint0", pos=(0, 0, 0), type="hinge"),
                E("body", name="body1", pos=(0.1, 0, 0), kids=[
                    E("joint", axis=(0, 0, 1), limited="true", name="joint1", pos=(0, 0, 0), range=(-3, 3), type="hinge"),
                    E("geom", fromto=(0, 0, 0, 0.1, 0, 0), name="link1", rgba=(0, 0.4, 0.6, 1), size=0.01, type="capsule"),
                    E("body", name="fingertip", pos=(0.11, 0, 0), kids=[
                        E("geom", contype=0, name="fingertip", pos=(0, 0, 0), rgba=(0, 0.8, 0.6, 1), size=0.01, type="sphere"),
                    ]),
                ]),
            ]),
            E("body", name="target", pos=(0.1, -0.1, 0.01), kids=[
                E("joint", armature=0, axis=(1, 0, 0), damping=0, limited="true", name="target_x", pos=(0, 0, 0), range=(-0.27, 0.27), ref=0.1, stiffness=0, type="slide"),
                E("joint", armature=0, axis=(0, 1, 0), damping=0, limited="true", name="target_y", pos=(0, 0, 0), range=(-0.27, 0.27), ref=-0.1, stiffness=0, type="slide"),
                E("geom", conaffinity=0, contype=0, name="target", pos=(0, 0, 0), rgba=(0.9, 0.2, 0.2, 1), size=0.009, type="sphere"),
            ]),
        ]),
        E("actuator", kids=[
            E("motor", ctrllimited="true", ctrlrange=(-1, 1), gear=200, joint="joint0"),
            E("motor", ctrllimited="true", ctrlrange=(-1, 1), gear=200, joint="joint1"),
        ]),
    ]),
    "swimmer.xml": E("mujoco", model="swimmer", kids=[
        E("compiler", angle="degree", coordinate="local", inertiafromgeom="true"),
        E("option", density=4000, integrator="RK4", timestep=0.01, viscosity=0.1),
        E("default", kids=[
            E("geom", conaffinity=0, condim=1, contype=0, material="geom", rgba=(0.8, 0.6, 0.4, 1)),
            E("joint", armature=0.1),
        ]),
        _textured_floor_assets(sky=(1, 1, 1), repeat=30),
        E("worldbody", kids=[
            _TOP_LIGHT,
            E("geom", condim=3, material="MatPlane", name="floor", pos=(0, 0, -0.1), rgba=(0.8, 0.9, 0.8, 1), size=(40, 40, 0.1), type="plane"),
            E("body", name="torso", pos=(0, 0, 0), kids=[
                E("camera", name="track", mode="trackcom", pos=(0, -3, 3), xyaxes=(1, 0, 0, 0, 1, 1)),
                E("geom", density=1000, fromto=(1.5, 0, 0, 0.5, 0, 0), size=0.1, type="capsule"),
                E("joint", axis=(1, 0, 0), name="slider1", pos=(0, 0, 0), type="slide"),
                E("joint", axis=(0, 1, 0), name="slider2", pos=(0, 0, 0), type="slide"),
                E("joint", axis=(0, 0, 1), name="free_body_rot", pos=(0, 0, 0), type="hinge"),
                E("body", name="mid", pos=(0.5, 0, 0), kids=[
                    E("geom", density=1000, fromto=(0, 0, 0, -1, 0, 0), size=0.1, type="capsule"),
                    E("joint", axis=(0, 0, 1), limited="true", name="motor1_rot", pos=(0, 0, 0), range=(-100, 100), type="hinge"),
                    E("body", name="back", pos=(-1, 0, 0), kids=[
                        E("geom", density=1000, fromto=(0, 0, 0, -1, 0, 0), size=0.1, type="capsule"),
                        E("joint", axis=(0, 0, 1), limited="true", name="motor2_rot", pos=(0, 0, 0), range=(-100, 100), type="hinge"),
                    ]),
                ]),
            ]),
        ]),
        E("actuator", kids=[
            E("motor", ctrllimited="true", ctrlrange=(-1, 1), gear=150, joint="motor1_rot"),
            E("motor", ctrllimited="true", ctrlrange=(-1, 1), gear=150, joint="motor2_rot"),
        ]),
    ]),
    "walker2d_v5.xml": E("mujoco", model="walker2d", kids=[
        E("compiler", angle="degree", inertiafromgeom="true"),
        E("default", kids=[
            E("joint", armature=0.01, damping=0.1, limited="true"),
            E("geom", conaffinity=0, condim=3, contype=1, density=1000, friction=(0.7, 0.1, 0.1), rgba=(0.8, 0.6, 0.4, 1)),
        ]),
        E("option", integrator="RK4", timestep=0.002),
        E("worldbody", kids=[
            _TOP_LIGHT,
            E("geom", conaffinity=1, condim=3, name="floor", pos=(0, 0, 0), rgba=(0.8, 0.9, 0.8, 1), size=(40, 40, 40), type="plane", material="MatPlane"),
            E("body", name="torso", pos=(0, 0, 1.25), kids=[
                E("camera", name="track", mode="trackcom", pos=(0, -3, -0.25), xyaxes=(1, 0, 0, 0, 0, 1)),
                E("joint", armature=0, axis=(1, 0, 0), damping=0, limited="false", name="rootx", pos=(0, 0, -1.25), stiffness=0, type="slide"),
                E("joint", armature=0, axis=(0, 0, 1), damping=0, limited="false", name="rootz", pos=(0, 0, -1.25), ref=1.25, stiffness=0, type="slide"),
                E("joint", armature=0, axis=(0, 1, 0), damping=0, limited="false", name="rooty", pos=(0, 0, 0), stiffness=0, type="hinge"),
                E("geom", friction=0.9, name="torso_geom", size=(0.05, 0.19999999999999996), type="capsule"),
                E("body", name="thigh", pos=(0, 0, -0.19999999999999996), kids=[
                    E("joint", axis=(0, -1, 0), name="thigh_joint", pos=(0, 0, 0), range=(-150, 0), type="hinge"),
                    E("geom", friction=0.9, pos=(0, 0, -0.2250000000000001), name="thigh_geom", size=(0.05, 0.22500000000000003), type="capsule"),
                    E("body", name="leg", pos=(0, 0, -0.7000000000000001), kids=[
                        E("joint", axis=(0, -1, 0), name="leg_joint", pos=(0, 0, 0.25), range=(-150, 0), type="hinge"),
                        E("geom", friction=0.9, name="leg_geom", size=(0.04, 0.25), type="capsule"),
                        E("body", name="foot", pos=(0.2, 0, -0.35), kids=[
                            E("joint", axis=(0, -1, 0), name="foot_joint", pos=(-0.2, 0, 0.1), range=(-45, 45), type="hinge"),
                            E("geom", friction=1.9, pos=(-0.1, 0, 0.1), quat=(0.7071067811865476, 0, -0.7071067811865475, 0), name="foot_geom", size=(0.06, 0.1), type="capsule"),
                        ]),
                    ]),
                ]),
                E("body", name="thigh_left", pos=(0, 0, -0.19999999999999996), kids=[
                    E("joint", axis=(0, -1, 0), name="thigh_left_joint", pos=(0, 0, 0), range=(-150, 0), type="hinge"),
                    E("geom", friction=0.9, name="thigh_left_geom", rgba=(0.7, 0.3, 0.6, 1), size=(0.05, 0.22500000000000003), pos=(0, 0, -0.2250000000000001), type="capsule"),
                    E("body", name="leg_left", pos=(0, 0, -0.7000000000000001), kids=[
                        E("joint", axis=(0, -1, 0), name="leg_left_joint", pos=(0, 0, 0.25), range=(-150, 0), type="hinge"),
                        E("geom", friction=0.9, name="leg_left_geom", rgba=(0.7, 0.3, 0.6, 1), size=(0.04, 0.25), type="capsule"),
                        E("body", name="foot_left", pos=(0.2, 0, -0.35), kids=[
                            E("joint", axis=(0, -1, 0), name="foot_left_joint", pos=(-0.2, 0, 0.1), range=(-45, 45), type="hinge"),
                            E("geom", friction=1.9, name="foot_left_geom", rgba=(0.7, 0.3, 0.6, 1), size=(0.06, 0.1), pos=(-0.1, 0, 0.1), type="capsule", quat=(0.7071067811865476, 0, -0.7071067811865475, 0)),
                        ]),
                    ]),
                ]),
            ]),
        ]),
        E("actuator", kids=[
            E("motor", ctrllimited="true", ctrlrange=(-1, 1), gear=100, joint="thigh_joint"),
            E("motor", ctrllimited="true", ctrlrange=(-1, 1), gear=100, joint="leg_joint"),
            E("motor", ctrllimited="true", ctrlrange=(-1, 1), gear=100, joint="foot_joint"),
            E("motor", ctrllimited="true", ctrlrange=(-1, 1), gear=100, joint="thigh_left_joint"),
            E("motor", ctrllimited="true", ctrlrange=(-1, 1), gear=100, joint="leg_left_joint"),
            E("motor", ctrllimited="true", ctrlrange=(-1, 1), gear=100, joint="foot_left_joint"),
        ]),
        _textured_floor_assets(sky=(0.4, 0.5, 0.6), repeat=60),
    ]),
}
# fmt: on


if __name__ == "__main__":
    for written in write_all(Path(sys.argv[1]) if len(sys.argv) > 1 else ASSETS):
        print(written)
