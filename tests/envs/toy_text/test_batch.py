"""Native toy-text batches: row i equals a single env seeded ``seed + i``, on both vector faces,
against Gymnasium's own ``SyncVectorEnv`` too."""

from __future__ import annotations

import warnings
from typing import Any

import numpy as np
import pytest
from tests.envs.toy_text.cases import VARIANTS, Policy, variant_id

import palaestra
from palaestra import error
from palaestra.envs import toy_text
from palaestra.vec_env import DummyVecEnv, make_vec_env
from palaestra.vector import AutoresetMode

N = 6
BATCHES = {
    "FrozenLake": (toy_text.FrozenLakeBatch, toy_text.FrozenLakeEnv),
    "CliffWalking": (toy_text.CliffWalkingBatch, toy_text.CliffWalkingEnv),
    "Taxi": (toy_text.TaxiBatch, toy_text.TaxiEnv),
    "Blackjack": (toy_text.BlackjackBatch, toy_text.BlackjackEnv),
}


def _classes(env_id: str) -> tuple[Any, Any]:
    return next(v for k, v in BATCHES.items() if env_id.startswith(k))


def _kwargs(env_id: str, kwargs: dict[str, Any]) -> dict[str, Any]:
    return {**palaestra.spec(env_id).kwargs, **kwargs}


def _rows(obs: Any) -> list[Any]:
    """Per-row observations of a batch (a tuple of arrays for Blackjack)."""
    if isinstance(obs, tuple):
        return [tuple(int(a[i]) for a in obs) for i in range(len(obs[0]))]
    return [int(o) for o in obs]


@pytest.mark.parametrize("case", VARIANTS, ids=variant_id)
def test_batch_rows_equal_single_envs(case: tuple[str, dict[str, Any]]) -> None:
    env_id, kwargs = case
    batch_cls, env_cls = _classes(env_id)
    kwargs = _kwargs(env_id, kwargs)
    batch = batch_cls(N, **kwargs)
    singles = [env_cls(**kwargs) for _ in range(N)]
    obs = batch.reset(seed=10)
    assert _rows(obs) == [env.reset(seed=10 + i)[0] for i, env in enumerate(singles)]
    policies = [Policy(env, i, 0.4) for i, env in enumerate(singles)]
    rng = np.random.default_rng(0)
    ends = 0
    ended = np.zeros(N, dtype=bool)
    for t in range(300):
        actions = np.array([p(o) for p, o in zip(policies, _rows(obs))])
        # Rows that ended are reset in place of a step, as autoreset does (their generator
        # draws a reset's numbers, not a step's); a few more are reset at random.
        reset = ended | (rng.random(N) < 0.02)
        obs, reward, terminated = batch.step(actions, reset)
        infos = batch.last_infos()
        want = []
        for i, env in enumerate(singles):
            if reset[i]:
                start, start_info = env.reset()
                want.append((start, 0.0, False, False, start_info))
            else:
                want.append(env.step(int(actions[i])))
        where = f"{variant_id(case)} step {t}"
        assert _rows(obs) == [w[0] for w in want], where
        np.testing.assert_array_equal(reward, [w[1] for w in want], err_msg=where)
        np.testing.assert_array_equal(terminated, [w[2] for w in want], err_msg=where)
        if infos is not None:
            for i, w in enumerate(want):
                for key, value in w[4].items():
                    np.testing.assert_array_equal(infos[i][key], value, err_msg=where)
        ended = terminated.copy()
        ends += int(ended.sum())
    assert ends > 0


def _same_infos(ours: dict[str, Any], ref: dict[str, Any], where: str) -> None:
    assert ours.keys() == ref.keys(), where
    for key, value in ref.items():
        if key == "final_obs":
            assert [
                o
                if o is None
                else _rows(np.atleast_1d(o))[0]
                if not isinstance(o, tuple)
                else tuple(int(x) for x in o)
                for o in ours[key]
            ] == [
                o if o is None else int(o) if not isinstance(o, tuple) else tuple(int(x) for x in o)
                for o in value
            ], where
        elif key == "final_info":
            _same_infos(ours[key], value, where)
        elif key == "prob" and value.dtype.kind == "i" and ours[key].dtype.kind == "f":
            # Gymnasium stacks with the dtype of the first row's value: when row 0 was just
            # reset (int 1), the other rows' probabilities are cut to 0 in an int array. Ours
            # stay float64; cut the same way, they are Gymnasium's.
            np.testing.assert_array_equal(ours[key].astype(value.dtype), value, err_msg=where)
        else:
            np.testing.assert_array_equal(ours[key], value, err_msg=f"{where} [{key}]")
            assert ours[key].dtype == value.dtype, (where, key)


def _same_obs(ours: Any, ref: Any, where: str) -> None:
    if isinstance(ref, tuple):
        for a, b in zip(ours, ref):
            np.testing.assert_array_equal(a, b, err_msg=where)
            assert a.dtype == b.dtype
    else:
        np.testing.assert_array_equal(ours, ref, err_msg=where)
        assert ours.dtype == ref.dtype


@pytest.mark.parametrize("mode", ["NextStep", "SameStep"])
@pytest.mark.parametrize("case", VARIANTS[::2], ids=variant_id)
def test_make_vec_matches_gymnasium_sync_vector_env(
    case: tuple[str, dict[str, Any]], mode: str
) -> None:
    gym = pytest.importorskip("gymnasium")
    env_id, kwargs = case
    vector_kwargs = {"autoreset_mode": mode}
    ours = palaestra.make_vec(env_id, num_envs=N, vector_kwargs=vector_kwargs, **kwargs)
    assert type(ours).__name__ == "BatchedVectorEnv"
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        ref = gym.make_vec(
            env_id,
            N,
            vectorization_mode="sync",
            vector_kwargs={"autoreset_mode": gym.vector.AutoresetMode(mode)},
            **kwargs,
        )
    assert ours.metadata["autoreset_mode"] == AutoresetMode(mode)
    obs, info = ours.reset(seed=3)
    ref_obs, ref_info = ref.reset(seed=3)
    _same_obs(obs, ref_obs, "reset")
    _same_infos(info, ref_info, "reset")
    policies = [Policy(ref.envs[i], i, 0.5) for i in range(N)]
    for t in range(200):
        actions = np.array([p(o) for p, o in zip(policies, _rows(ref_obs))])
        got, want = ours.step(actions), ref.step(actions)
        where = f"step {t}"
        _same_obs(got[0], want[0], where)
        for a, b in zip(got[1:4], want[1:4]):
            np.testing.assert_array_equal(a, b, err_msg=where)
        _same_infos(got[4], want[4], where)
        ref_obs = want[0]
    ours.close()
    ours.close()


@pytest.mark.parametrize("case", VARIANTS[1::3], ids=variant_id)
def test_make_vec_env_matches_dummy_vec_env(case: tuple[str, dict[str, Any]]) -> None:
    env_id, kwargs = case
    native = make_vec_env(env_id, n_envs=N, seed=5, env_kwargs=kwargs)
    assert type(native.venv).__name__ == "BatchedVecEnv"
    loop = make_vec_env(env_id, n_envs=N, seed=5, env_kwargs=kwargs, vec_env_cls=DummyVecEnv)
    obs, ref_obs = native.reset(), loop.reset()
    _same_obs(obs, ref_obs, "reset")
    policies = [Policy(palaestra.make(env_id, **kwargs), i, 0.5) for i in range(N)]
    finished = 0
    for t in range(250):
        actions = np.array([p(o) for p, o in zip(policies, _rows(ref_obs))])
        obs, rewards, dones, infos = native.step(actions)
        ref_obs, ref_rewards, ref_dones, ref_infos = loop.step(actions)
        where = f"step {t}"
        _same_obs(obs, ref_obs, where)
        np.testing.assert_array_equal(rewards, ref_rewards, err_msg=where)
        assert rewards.dtype == ref_rewards.dtype
        np.testing.assert_array_equal(dones, ref_dones, err_msg=where)
        for got, want in zip(infos, ref_infos):
            assert got.keys() == want.keys(), where
            for key, value in want.items():
                if key == "episode":
                    assert (got[key]["r"], got[key]["l"]) == (value["r"], value["l"]), where
                elif key == "terminal_observation" and isinstance(value, tuple):
                    assert tuple(map(int, got[key])) == tuple(map(int, value)), where
                else:
                    np.testing.assert_array_equal(got[key], value, err_msg=where)
        finished += int(dones.sum())
    assert finished > 0
    native.close()
    loop.close()


def test_seeds_list_and_unseeded_rows_keep_their_generator() -> None:
    batch = toy_text.FrozenLakeBatch(3)
    batch.reset(seed=[5, None, 7])
    assert batch.seeds[0] == 5 and batch.seeds[2] == 7 and batch.seeds[1] is not None
    first = batch.seeds[1]
    batch.reset(seed=[None, None, 1])
    assert batch.seeds[:2] == [5, first] and batch.seeds[2] == 1


def test_batch_errors() -> None:
    batch = toy_text.TaxiBatch(4)
    with pytest.raises(error.ResetNeeded, match=r"Rows \[0, 1, 2, 3\] were never reset"):
        batch.step(np.zeros(4, dtype=np.int64))
    batch.reset(seed=0)
    with pytest.raises(
        error.InvalidAction, match=r"rows \[2\]: \[6\] not in action space Discrete\(6\)"
    ):
        batch.step(np.array([0, 1, 6, 2]))
    with pytest.raises(error.InvalidAction, match="expected 4 integers"):
        batch.step(np.array([0.0, 1.0, 2.0, 3.0]))
    with pytest.raises(error.InvalidAction, match="expected 4 integers"):
        batch.step([0, 1])
    with pytest.raises(ValueError, match="Expected 4 seeds, got 2"):
        batch.reset(seed=[1, 2])
    with pytest.raises(ValueError, match="mask must be a bool array of shape"):
        batch.reset(mask=np.ones(3, dtype=bool))
    for bad in (0, -2, 2.5, True):
        with pytest.raises(ValueError, match="num_envs must be a positive integer"):
            toy_text.BlackjackBatch(bad)  # type: ignore[arg-type]


def test_vector_env_rejects_bad_actions_by_row() -> None:
    envs = palaestra.make_vec("CliffWalking-v1", num_envs=3)
    envs.reset(seed=0)
    with pytest.raises(error.InvalidAction, match=r"rows \[1\]: \[-1\]"):
        envs.step(np.array([0, -1, 2]))


def test_blackjack_slow_path_draws_the_same(monkeypatch: pytest.MonkeyPatch) -> None:
    """The two-part step (what runs when the one-pass step gives up), with no values read
    beyond the cards, so that resets also take the one-at-a-time path (the one a rejected
    draw would take): rows still equal single envs."""
    batch = toy_text.BlackjackBatch(N)
    monkeypatch.setattr(batch, "_step_all", lambda actions, resetting: None)
    streams = batch._streams
    exact = type(streams).peek_bounded
    monkeypatch.setattr(streams, "peek_bounded", lambda *a, **k: exact(streams, *a, slack=0))
    singles = [toy_text.BlackjackEnv() for _ in range(N)]
    obs = batch.reset(seed=50)
    assert _rows(obs) == [env.reset(seed=50 + i)[0] for i, env in enumerate(singles)]
    rng = np.random.default_rng(2)
    ended = np.zeros(N, dtype=bool)
    for _ in range(200):
        actions = rng.integers(0, 2, N)
        obs, reward, terminated = batch.step(actions, ended)
        want = [(*env.reset(), 0.0, False) if ended[i] else env.step(int(actions[i]))
                for i, env in enumerate(singles)]  # fmt: skip
        want = [(w[0], w[2], w[3]) if ended[i] else (w[0], w[1], w[2]) for i, w in enumerate(want)]
        assert _rows(obs) == [w[0] for w in want]
        np.testing.assert_array_equal(reward, [w[1] for w in want])
        np.testing.assert_array_equal(terminated, [w[2] for w in want])
        ended = terminated.copy()
    assert [s.dealer_top_card_suit for s in singles] == [
        toy_text.blackjack.SUITS[k] for k in batch._suit
    ]


def _blackjack_against_singles(
    batch: toy_text.BlackjackBatch, steps: int, seed: int, autoreset: bool
) -> None:
    """Step ``batch`` with random actions (resetting ended rows in the step when
    ``autoreset``, else by ``reset(mask=...)``) and compare every row with a single env."""
    n = batch.num_envs
    kwargs = {"natural": batch.natural, "sab": batch.sab}
    singles = [toy_text.BlackjackEnv(**kwargs) for _ in range(n)]
    obs = batch.reset(seed=seed)
    assert _rows(obs) == [env.reset(seed=seed + i)[0] for i, env in enumerate(singles)]
    rng = np.random.default_rng(seed)
    ended = np.zeros(n, dtype=bool)
    for t in range(steps):
        actions = rng.integers(0, 2, n)
        if autoreset:
            obs, reward, terminated = batch.step(actions, ended)
        else:
            if ended.any():
                batch.reset(mask=ended)
            obs, reward, terminated = batch.step(actions)
        want = []
        for i, env in enumerate(singles):
            if ended[i] and autoreset:
                want.append((env.reset()[0], 0.0, False))
                continue
            if ended[i]:
                env.reset()
            want.append(env.step(int(actions[i]))[:3])
        assert _rows(obs) == [w[0] for w in want], f"step {t}"
        np.testing.assert_array_equal(reward, [w[1] for w in want], err_msg=f"step {t}")
        np.testing.assert_array_equal(terminated, [w[2] for w in want], err_msg=f"step {t}")
        ended = terminated.copy()
    assert [s.dealer_top_card_suit for s in singles] == [
        toy_text.blackjack.SUITS[k] for k in batch._suit
    ]
    tens = [s.dealer[0] == 10 for s in singles]
    faces = [s.dealer_top_card_value_str for s, ten in zip(singles, tens) if ten]
    assert faces == [toy_text.blackjack.FACES[k] for k in batch._face[np.array(tens)]]


@pytest.mark.parametrize("kwargs", [{}, {"natural": True}, {"sab": True}])
@pytest.mark.parametrize("autoreset", [True, False])
def test_blackjack_one_pass_step_at_many_rows(kwargs: dict[str, bool], autoreset: bool) -> None:
    """The one-pass step (every step here unless a rare fallback) at 256 rows, with the
    deal in the step (autoreset) or by a masked reset."""
    batch = toy_text.BlackjackBatch(256, **kwargs)
    calls = []
    one_pass = batch._step_all

    def counted(actions: np.ndarray, resetting: np.ndarray | None) -> Any:
        out = one_pass(actions, resetting)
        calls.append(out is not None)
        return out

    batch._step_all = counted  # type: ignore[method-assign]
    _blackjack_against_singles(batch, 40, seed=7, autoreset=autoreset)
    assert sum(calls) >= 39  # fallbacks are rare: one step in thousands at this size


def test_blackjack_one_pass_step_falls_back_exactly(monkeypatch: pytest.MonkeyPatch) -> None:
    """Allowing a dealer one draw in the one-pass step makes it give up whenever a dealer
    needs two (about 1 in 5 hands): steps then alternate between the two paths, and every
    row still equals its single env."""
    batch = toy_text.BlackjackBatch(16)
    monkeypatch.setattr(batch, "max_dealer_draws", 1)
    calls = []
    one_pass = batch._step_all

    def counted(actions: np.ndarray, resetting: np.ndarray | None) -> Any:
        out = one_pass(actions, resetting)
        calls.append(out is not None)
        return out

    monkeypatch.setattr(batch, "_step_all", counted)
    _blackjack_against_singles(batch, 300, seed=11, autoreset=True)
    assert 30 < sum(calls) < 270, sum(calls)  # both paths ran, many times


def test_blackjack_dealer_tables_match_the_rules() -> None:
    """The dealer's code tables against the hand rules: a code draws iff its total is below
    17, and a card adds its value (an ace sets the flag)."""
    bj = toy_text.blackjack
    for code in range(bj._DEALER_CODES):
        raw, ace = code >> 1, bool(code & 1)
        assert bj._DEALER_DRAWS[code] == (bj.total(bj.SCALAR, raw, ace) < 17)
        for card in range(1, 11):
            nxt = bj._DEALER_NEXT[11 * code + card]
            if bj._DEALER_DRAWS[code]:
                assert (nxt >> 1, bool(nxt & 1)) == (raw + card, ace or card == 1)
            else:
                assert nxt == code
    assert not bj._DEALER_DRAWS[bj._DEALER_STOPPED]


def test_disabled_autoreset_and_partial_resets_report_reset_infos() -> None:
    envs = palaestra.make_vec("Taxi-v4", num_envs=3, vector_kwargs={"autoreset_mode": "Disabled"})
    envs.reset(seed=0)
    mask = np.array([False, True, False])
    obs, infos = envs.reset(seed=9, options={"reset_mask": mask})
    single, single_info = palaestra.make("Taxi-v4").reset(seed=10)  # row 1 gets seed 9 + 1
    assert obs[1] == single
    np.testing.assert_array_equal(infos["_prob"], mask)
    np.testing.assert_array_equal(infos["action_mask"][1], single_info["action_mask"])
    assert infos["prob"].tolist() == [0.0, 1.0, 0.0]  # rows without an info read 0
    cliff = palaestra.make_vec(
        "CliffWalking-v1", num_envs=2, vector_kwargs={"autoreset_mode": "Disabled"}
    )
    cliff.reset(seed=0)
    cliff.step(np.array([1, 0]))  # row 0 steps right from the start: onto the cliff, not ended
    # Up, then down, then right x11, then down: the goal ends row 0.
    for action in [0] + [1] * 11 + [2]:
        _, _, terminated, _, _ = cliff.step(np.array([action, 0]))
    assert terminated.tolist() == [True, False]
    with pytest.raises(error.ResetNeeded, match=r"Sub-environments \[0\] have finished"):
        cliff.step(np.array([0, 0]))


@pytest.mark.parametrize("case", [VARIANTS[0], VARIANTS[10], VARIANTS[12]], ids=variant_id)
def test_run_state_round_trip_continues_exactly(case: tuple[str, dict[str, Any]]) -> None:
    from palaestra.utils import run_state

    env_id, kwargs = case
    batch_cls, _ = _classes(env_id)
    batch = batch_cls(N, **_kwargs(env_id, kwargs))
    batch.reset(seed=4)
    rng = np.random.default_rng(0)
    n = int(batch.single_action_space.n)
    ended = np.zeros(N, dtype=bool)

    def run(steps: int) -> list[Any]:
        nonlocal ended
        out = []
        for _ in range(steps):
            obs, reward, terminated = batch.step(rng.integers(0, n, N), ended)
            out.append((_rows(obs), reward.tolist(), terminated.tolist()))
            ended = terminated.copy()
        return out

    run(150)
    saved, saved_ended, saved_rng = run_state.capture(batch), ended.copy(), rng.bit_generator.state
    first = run(300)
    run_state.restore(batch, saved)
    ended, rng.bit_generator.state = saved_ended, saved_rng
    assert run(300) == first
