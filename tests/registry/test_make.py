"""make(): the wrapper stack, spec bookkeeping, kwargs, render modes and errors."""

from __future__ import annotations

import warnings
from typing import Any, ClassVar

import gymnasium
import numpy as np
import pytest
from tests.registry.toys import PalToy, ScaleReward, Unrecorded, prewrapped_toy

import palaestra.envs.registration as registration
from palaestra import error
from palaestra.envs.registration import EnvSpec, WrapperSpec, make, register, registry
from palaestra.wrappers.common import OrderEnforcing, PassiveEnvChecker, TimeLimit

STACK = "<TimeLimit<OrderEnforcing<PassiveEnvChecker<ToyEnv<PalTest/Toy-v3>>>>>"


def test_stack_and_str_match_gymnasium(toy_ids: tuple[str, ...]) -> None:
    env = make("PalTest/Toy-v3")
    assert str(env) == repr(env) == STACK == str(gymnasium.make("PalTest/Toy-v3"))
    assert isinstance(env, TimeLimit)
    assert isinstance(env.env, OrderEnforcing)
    assert isinstance(env.env.env, PassiveEnvChecker)
    assert type(env.unwrapped) is PalToy


def test_spec_describes_the_stack(toy_ids: tuple[str, ...]) -> None:
    env = make("PalTest/Toy-v3", size=3)
    gym_env = gymnasium.make("PalTest/Toy-v3", size=3)
    fields = ("id", "max_episode_steps", "order_enforce", "disable_env_checker", "kwargs")
    for spec_of in (lambda e: e.spec, lambda e: e.unwrapped.spec):
        pal, gym = spec_of(env), spec_of(gym_env)
        assert [getattr(pal, f) for f in fields] == [getattr(gym, f) for f in fields]
    assert env.spec is not None and env.spec.additional_wrappers == ()
    assert str(make(env.spec)) == STACK


def test_kwargs_override_without_touching_the_registry(toy_ids: tuple[str, ...]) -> None:
    registry["PalTest/Toy-v3"].kwargs = {"size": 2}
    env = make("PalTest/Toy-v3", size=5)
    assert env.observation_space.shape == (5,)
    assert env.unwrapped.spec is not None and env.unwrapped.spec.kwargs == {"size": 5}
    assert registry["PalTest/Toy-v3"].kwargs == {"size": 2}
    assert make("PalTest/Toy-v3").observation_space.shape == (2,)


def test_max_episode_steps_override_and_truncation(toy_ids: tuple[str, ...]) -> None:
    env = make("PalTest/Toy-v3", max_episode_steps=2)
    assert env.spec is not None and env.spec.max_episode_steps == 2
    env.reset(seed=0)
    assert [env.step(0)[3] for _ in range(2)] == [False, True]
    env.reset()
    assert env.step(1)[3] is False
    assert not isinstance(make("PalTest/Toy-v3", max_episode_steps=-1), TimeLimit)
    assert not isinstance(make("PalTest/Plain"), TimeLimit)  # spec has no limit
    with pytest.raises(ValueError, match="to be positive, actually: 0"):
        make("PalTest/Toy-v3", max_episode_steps=0)


def test_disable_env_checker_and_order_enforce(clean_registry: None) -> None:
    register("NoCheck-v0", entry_point=PalToy, disable_env_checker=True, order_enforce=False)
    assert str(make("NoCheck-v0")) == "<ToyEnv<NoCheck-v0>>"
    assert str(make("NoCheck-v0", disable_env_checker=False)) == (
        "<PassiveEnvChecker<ToyEnv<NoCheck-v0>>>"
    )
    register("Checked-v0", entry_point=PalToy)
    assert str(make("Checked-v0", disable_env_checker=True)) == (
        "<OrderEnforcing<ToyEnv<Checked-v0>>>"
    )
    spec = make("Checked-v0", disable_env_checker=True).spec
    assert spec is not None and spec.disable_env_checker is True


def test_step_before_reset_raises(toy_ids: tuple[str, ...]) -> None:
    env = make("PalTest/Toy-v3")
    with pytest.raises(
        error.ResetNeeded, match=r"Cannot call env.step\(\) before calling env.reset\(\)"
    ):
        env.step(0)


def test_seeded_make_matches_gymnasium(toy_ids: tuple[str, ...]) -> None:
    env, gym_env = make("PalTest/Toy-v3"), gymnasium.make("PalTest/Toy-v3")
    obs, _ = env.reset(seed=7)
    gym_obs, _ = gym_env.reset(seed=7)
    np.testing.assert_array_equal(obs, gym_obs)
    for action in (1, 1, 0, 1, 0):
        ours, theirs = env.step(action), gym_env.step(action)
        np.testing.assert_array_equal(ours[0], theirs[0])
        assert ours[1:4] == theirs[1:4]


def test_additional_wrappers_are_rebuilt_from_the_spec(toy_ids: tuple[str, ...]) -> None:
    env = ScaleReward(make("PalTest/Toy-v3"), scale=2.0)
    assert env.spec is not None
    assert env.spec.additional_wrappers == (
        WrapperSpec("ScaleReward", "tests.registry.toys:ScaleReward", {"scale": 2.0}),
    )
    for spec in (env.spec, EnvSpec.from_json(env.spec.to_json())):
        rebuilt = make(spec)
        assert str(rebuilt) == f"<ScaleReward{STACK}>"
        rebuilt.reset(seed=0)
        assert rebuilt.step(0)[1] == 2.0


def test_unrecorded_wrapper_cannot_be_rebuilt(toy_ids: tuple[str, ...]) -> None:
    env = Unrecorded(make("PalTest/Toy-v3"))
    assert env.spec is not None and env.spec.additional_wrappers[0].kwargs is None
    with pytest.raises(ValueError, match="Unrecorded wrapper does not inherit from"):
        make(env.spec)


def test_wrappers_applied_by_the_entry_point_are_not_applied_twice(clean_registry: None) -> None:
    scale3 = WrapperSpec("ScaleReward", "tests.registry.toys:ScaleReward", {"scale": 3.0})
    register("Pre-v0", entry_point=prewrapped_toy, additional_wrappers=(scale3,))
    env = make("Pre-v0")
    assert str(env) == "<OrderEnforcing<PassiveEnvChecker<ScaleReward<ToyEnv<Pre-v0>>>>>"
    env.reset(seed=0)
    assert env.step(0)[1] == 3.0
    scale4 = WrapperSpec("ScaleReward", "tests.registry.toys:ScaleReward", {"scale": 4.0})
    register("PreBad-v0", entry_point=prewrapped_toy, additional_wrappers=(scale4,))
    with pytest.raises(
        ValueError, match="is different from the saved `EnvSpec` additional wrapper"
    ):
        make("PreBad-v0")


def test_bad_ids_and_entry_points(clean_registry: None) -> None:
    with pytest.raises(TypeError, match="Expected id to be a string or EnvSpec, got <class 'int'>"):
        make(3)  # type: ignore[arg-type]
    register("VecOnly-v0", vector_entry_point="somewhere:Vec")
    with pytest.raises(error.Error, match="VecOnly-v0 registered but entry_point is not specified"):
        make("VecOnly-v0")
    register("NotAnEnv-v0", entry_point=lambda: object())
    with pytest.raises(TypeError, match=r"must inherit from the palaestra\.Env class"):
        make("NotAnEnv-v0")
    register("Toy-v0", entry_point=PalToy)
    with pytest.raises(
        TypeError,
        match=r"was raised from the environment creator for Toy-v0 with kwargs \({'colour': 1}\)",
    ):
        make("Toy-v0", colour=1)
    register("Missing-v0", entry_point="tests.registry.toys:NoSuchEnv")
    with pytest.raises(AttributeError, match="NoSuchEnv"):
        make("Missing-v0")


class _BadMetadata(PalToy):  # type: ignore[misc,valid-type]
    metadata: ClassVar[Any] = ["rgb_array"]


class _NoRenderModes(PalToy):  # type: ignore[misc,valid-type]
    metadata: ClassVar[dict[str, Any]] = {"render_fps": 4}


def test_render_mode_handling(clean_registry: None) -> None:
    register("Toy-v0", entry_point=PalToy)
    assert make("Toy-v0", render_mode="rgb_array").render_mode == "rgb_array"
    with pytest.warns(UserWarning, match=r"render_mode='depth_array' that is not in the possible"):
        make("Toy-v0", render_mode="depth_array")
    register("BadMeta-v0", entry_point=_BadMetadata)
    with pytest.raises(error.InvalidMetadata, match="Expect the environment metadata to be dict"):
        make("BadMeta-v0")
    register("NoModes-v0", entry_point=_NoRenderModes)
    with pytest.warns(UserWarning, match="metadata doesn't include `render_modes`"):
        make("NoModes-v0", disable_env_checker=True)


class _OldRenderApi(PalToy):  # type: ignore[misc,valid-type]
    metadata: ClassVar[dict[str, Any]] = {"render_modes": ["rgb_array"], "render_fps": 4}

    def __init__(self) -> None:
        super().__init__()


class _ModesNotIterable(PalToy):  # type: ignore[misc,valid-type]
    metadata: ClassVar[dict[str, Any]] = {"render_modes": 3, "render_fps": 4}


def test_render_mode_edge_cases(clean_registry: None) -> None:
    register("Old-v0", entry_point=_OldRenderApi)
    with pytest.warns(UserWarning, match="HumanRendering wrapper is being applied"):
        with pytest.raises(error.Error, match="doesn't implement human-rendering natively"):
            make("Old-v0", render_mode="human")
    register("Odd-v0", entry_point=_ModesNotIterable)
    with pytest.warns(UserWarning, match="render_modes to be a Iterable"):
        env = make("Odd-v0", render_mode="rgb_array", disable_env_checker=True)
    assert env.unwrapped.render_mode == "rgb_array"


def test_render_mode_wrappers(clean_registry: None) -> None:
    rendering = pytest.importorskip("palaestra.wrappers.rendering")
    register("Toy-v0", entry_point=PalToy)
    env = make("Toy-v0", render_mode="rgb_array_list")
    assert isinstance(env, rendering.RenderCollection)
    assert env.unwrapped.render_mode == "rgb_array"
    with pytest.warns(UserWarning, match="The HumanRendering wrapper is being applied"):
        human = make("Toy-v0", render_mode="human")
    assert isinstance(human, rendering.HumanRendering)
    human.close()


def test_make_vec_validates_before_vectorizing(toy_ids: tuple[str, ...]) -> None:
    with pytest.raises(error.Error, match="Invalid id type: <class 'int'>"):
        registration.make_vec(3)  # type: ignore[arg-type]
    with pytest.raises(error.NameNotFound):
        registration.make_vec("PalTest/Nope-v0")
    with pytest.raises(ValueError) as pal:
        registration.make_vec("PalTest/Toy-v3", vectorization_mode="x")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        with pytest.raises(ValueError) as gym:
            gymnasium.make_vec("PalTest/Toy-v3", vectorization_mode="x")
    assert str(pal.value) == str(gym.value)
    with pytest.raises(error.Error, match="doesn't have a vector entry point defined"):
        registration.make_vec("PalTest/Toy-v3", vectorization_mode="vector_entry_point")


class _FakeVectorEnv:
    metadata: ClassVar[dict[str, Any]] = {}
    spec: EnvSpec | None = None

    def __init__(self, num_envs: int, **kwargs: Any) -> None:
        self.num_envs, self.kwargs = num_envs, kwargs

    @property
    def unwrapped(self) -> _FakeVectorEnv:
        return self


def test_make_vec_with_a_vector_entry_point(
    clean_registry: None, monkeypatch: pytest.MonkeyPatch
) -> None:
    from palaestra.vector import AutoresetMode

    monkeypatch.setattr(_FakeVectorEnv, "metadata", {"autoreset_mode": AutoresetMode.NEXT_STEP})
    register("Vec-v0", vector_entry_point=_FakeVectorEnv, max_episode_steps=9, kwargs={"a": 1})
    env = registration.make_vec("Vec-v0", num_envs=4, b=2)
    assert (env.num_envs, env.kwargs) == (4, {"a": 1, "b": 2, "max_episode_steps": 9})
    assert env.spec.kwargs["vectorization_mode"] == "vector_entry_point"
    assert env.spec.kwargs["num_envs"] == 4
    again = registration.make_vec(env.spec)  # the saved make_vec arguments are reused
    assert again.num_envs == 4
    with pytest.raises(error.Error, match="`vector_kwargs` is not empty"):
        registration.make_vec("Vec-v0", vector_kwargs={"copy": False})
    with pytest.raises(error.Error, match="with the wrappers argument"):
        registration.make_vec("Vec-v0", wrappers=[ScaleReward])
    with pytest.raises(error.Error, match="doesn't have an entry point defined"):
        registration.make_vec("Vec-v0", vectorization_mode="sync")


@pytest.mark.parametrize("mode", ["sync", "async"])
def test_make_vec_matches_gymnasium(toy_ids: tuple[str, ...], mode: str) -> None:
    env = registration.make_vec("PalTest/Toy-v3", num_envs=2, vectorization_mode=mode)
    gym_env = gymnasium.make_vec("PalTest/Toy-v3", num_envs=2, vectorization_mode=mode)
    try:
        np.testing.assert_array_equal(env.reset(seed=3)[0], gym_env.reset(seed=3)[0])
        assert env.spec.kwargs == {"num_envs": 2, "vectorization_mode": mode}
    finally:
        env.close()
        gym_env.close()


def test_make_vec_warns_about_missing_autoreset_metadata(clean_registry: None) -> None:
    register("Vec-v0", vector_entry_point=_FakeVectorEnv)
    with pytest.warns(UserWarning, match="is missing AutoresetMode metadata"):
        registration.make_vec("Vec-v0", num_envs=2)
    _FakeVectorEnv.metadata = {"autoreset_mode": "next_step"}
    try:
        with pytest.warns(UserWarning, match=r"metadata\['autoreset_mode'\] is not an instance"):
            registration.make_vec("Vec-v0", num_envs=2)
    finally:
        _FakeVectorEnv.metadata = {}
