"""Custom policy classes and features extractors for DQN, SAC, TD3 and DDPG (issue 16), as SB3
2.x takes them: ``policy_kwargs=dict(features_extractor_class=..., share_features_extractor=...)``
and a subclass of the algorithm's policy class (``DQNPolicy``, ``SACPolicy``, ``TD3Policy``,
SB3's ``MlpPolicy``/``CnnPolicy``/``MultiInputPolicy`` aliases) passed as ``policy``. Ported in
spirit from SB3's ``tests/test_custom_policy.py``, with the same classes written over either
library's base classes and built side by side with the installed SB3."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pytest
import torch
from torch import nn

from palaestra.algos import DDPG, DQN, SAC, TD3, ModelFileError
from palaestra.algos import dqn as dqn_module
from palaestra.algos import sac as sac_module
from palaestra.algos import td3 as td3_module
from palaestra.algos.common.continuous_policies import (
    ContinuousCritic,
    DeterministicActor,
    SquashedGaussianActor,
)
from palaestra.algos.dqn import DQNPolicy, QNetwork
from palaestra.algos.networks import BaseFeaturesExtractor, CombinedExtractor, NatureCNN
from palaestra.algos.sac import SACPolicy
from palaestra.algos.td3 import TD3Policy

from .toys import Toy

sb3 = pytest.importorskip("stable_baselines3")
sb3_layers = pytest.importorskip("stable_baselines3.common.torch_layers")
compat = pytest.importorskip("palaestra.compat")

SMALL = {"learning_starts": 16, "batch_size": 8, "buffer_size": 200}
ALGOS = {"DQN": DQN, "SAC": SAC, "TD3": TD3, "DDPG": DDPG}
ENV_OF = {"DQN": "CartPole-v1", "SAC": "Pendulum-v1", "TD3": "Pendulum-v1", "DDPG": "Pendulum-v1"}
POLICY_OF = {"DQN": DQNPolicy, "SAC": SACPolicy, "TD3": TD3Policy, "DDPG": TD3Policy}


def tiny_mlp(base: type) -> type:
    """A features extractor for vector observations, over ``base`` (SB3's or palaestra's)."""

    class TinyMlp(base):  # type: ignore[misc,valid-type]
        def __init__(self, observation_space: Any, features_dim: int = 8) -> None:
            super().__init__(observation_space, features_dim)
            width = int(np.prod(observation_space.shape))
            self.net = nn.Sequential(nn.Flatten(), nn.Linear(width, features_dim), nn.Tanh())

        def forward(self, observations: torch.Tensor) -> torch.Tensor:
            return self.net(observations)

    return TinyMlp


OURS_MLP, THEIRS_MLP = tiny_mlp(BaseFeaturesExtractor), tiny_mlp(sb3_layers.BaseFeaturesExtractor)


class LayerNormActor(SquashedGaussianActor):
    """A SAC actor whose latent is layer-normalised (a make_actor override)."""

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        self.norm = nn.LayerNorm(self.mu.in_features)

    def latent(self, obs: Any) -> torch.Tensor:
        return self.norm(super().latent(obs))


class NormSACPolicy(SACPolicy):
    """SB3's guide: a subclass overriding ``make_actor``; ``hidden`` is its own keyword."""

    def __init__(self, *args: Any, hidden: int = 32, **kwargs: Any) -> None:
        self.hidden = hidden
        super().__init__(*args, **{**kwargs, "net_arch": dict(pi=[hidden], qf=[16, 16])})

    def make_actor(self, features_extractor: Any = None) -> SquashedGaussianActor:
        return LayerNormActor(
            self.observation_space,
            self.action_dim,
            features_extractor or self.make_features_extractor(),
            self.actor_arch,
            self.activation_fn,
            self.normalize_images,
        )


class WideCriticTD3Policy(TD3Policy):
    """A TD3/DDPG policy whose critics (only) are built wider, by a ``make_critic`` override."""

    def make_critic(self, features_extractor: Any = None) -> ContinuousCritic:
        critic = super().make_critic(features_extractor)
        assert critic.q_networks[0][0].out_features == self.critic_arch[0]
        return ContinuousCritic(
            self.observation_space,
            self.action_dim,
            critic.features_extractor,
            [48],
            nn.Tanh,
            n_critics=self.n_critics,
            share_features_extractor=self.share_features_extractor,
        )


class DuelingishQNetwork(QNetwork):
    """A Q-network with a LayerNorm before the head (a ``make_q_net`` override)."""

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        self.norm = nn.LayerNorm(self.head.in_features)

    def forward(self, obs: Any) -> torch.Tensor:
        from palaestra.algos.networks import preprocess_obs

        x = preprocess_obs(obs, self.observation_space, self.normalize_images)
        return self.head(self.norm(self.mlp(self.features_extractor(x))))


class NormDQNPolicy(DQNPolicy):
    def make_q_net(self) -> QNetwork:
        return DuelingishQNetwork(
            self.observation_space,
            self.action_space,
            self.features_extractor_class,
            self.features_extractor_kwargs,
            [16],
            self.activation_fn,
            self.normalize_images,
        )


CUSTOM = {"DQN": NormDQNPolicy, "SAC": NormSACPolicy, "TD3": WideCriticTD3Policy}
CUSTOM["DDPG"] = WideCriticTD3Policy


def _torch_learner(model: Any, why: str) -> None:
    assert model.learner.describe() == f"torch learner (numpy cannot: {why})"


def _probe(algo: str) -> np.ndarray:
    width = 4 if algo == "DQN" else 3
    return np.random.default_rng(1).normal(size=(6, width)).astype(np.float32)


# -- the names --------------------------------------------------------------------------------
def test_sb3_policy_names_and_paths() -> None:
    for module, base in [(dqn_module, DQNPolicy), (sac_module, SACPolicy), (td3_module, TD3Policy)]:
        assert module.MlpPolicy is base
        assert issubclass(module.CnnPolicy, base) and issubclass(module.MultiInputPolicy, base)
        assert module.CnnPolicy.default_features_extractor_class is NatureCNN
        assert module.MultiInputPolicy.default_features_extractor_class is CombinedExtractor
        algo = {dqn_module: DQN, sac_module: SAC, td3_module: TD3}[module]
        assert algo.policy_aliases == {
            "MlpPolicy": module.MlpPolicy,
            "CnnPolicy": module.CnnPolicy,
            "MultiInputPolicy": module.MultiInputPolicy,
        }
    assert DDPG.policy_aliases is TD3.policy_aliases  # SB3's DDPG uses TD3's policies


@pytest.mark.parametrize("algo", ["DQN", "SAC", "TD3", "DDPG"])
def test_the_policy_class_itself_is_the_policy_name(tmp_path: Path, algo: str) -> None:
    """``MlpPolicy`` the class builds what ``"MlpPolicy"`` the name builds (same seed, same
    weights), on the same (numpy) learner, and is what ``model.policy`` is; palaestra's own
    classes load back without ``custom_objects``."""
    cls = ALGOS[algo]
    by_name = cls("MlpPolicy", ENV_OF[algo], seed=3, buffer_size=100)
    by_class = cls(POLICY_OF[algo], ENV_OF[algo], seed=3, buffer_size=100)
    assert type(by_name.policy) is type(by_class.policy) is POLICY_OF[algo]
    mine, theirs = by_name.policy.state_dict(), by_class.policy.state_dict()
    assert list(mine) == list(theirs)
    assert all(torch.equal(mine[k], theirs[k]) for k in mine)
    assert by_class.learner.describe() == by_name.learner.describe()
    assert by_class.learner.describe().startswith("numpy")
    by_class.save(tmp_path / "ours")
    assert type(ALGOS[algo].load(tmp_path / "ours").policy) is POLICY_OF[algo]
    if algo == "DQN":  # SB3's policy(obs): the greedy actions
        obs = _probe(algo)
        greedy = by_class.policy(torch.as_tensor(obs)).numpy()
        np.testing.assert_array_equal(greedy, by_class.predict(obs, deterministic=True)[0])


def test_policy_state_keys_are_sb3s() -> None:
    """The parts sit under SB3's names (``actor.``, ``critic.qf0.``, ``q_net.`` ...)."""
    for algo, roots in [
        ("DQN", {"q_net", "q_net_target"}),
        ("SAC", {"actor", "critic", "critic_target", "ent_coef"}),
        ("TD3", {"actor", "actor_target", "critic", "critic_target"}),
    ]:
        small = dict(buffer_size=100, policy_kwargs=dict(net_arch=[8]))
        model = ALGOS[algo]("MlpPolicy", ENV_OF[algo], **small)
        assert {k.split(".")[0] for k in model.policy.state_dict()} == roots
        theirs = getattr(sb3, algo)("MlpPolicy", ENV_OF[algo], **small)
        sb3_roots = {k.split(".")[0] for k in theirs.policy.state_dict()}
        assert sb3_roots == roots - {"ent_coef"}  # SB3 keeps log_ent_coef on the model


# -- features extractors ----------------------------------------------------------------------
def _copy_params(src: nn.Module, dst: nn.Module) -> None:
    """Copy ``src``'s parameters into ``dst``'s, in order (the layouts are SB3's)."""
    src_params, dst_params = list(src.parameters()), list(dst.parameters())
    assert [p.shape for p in src_params] == [p.shape for p in dst_params]
    with torch.no_grad():
        for s, d in zip(src_params, dst_params):
            d.copy_(s)


@pytest.mark.parametrize(
    ("algo", "share"),
    # DQN has one network (SB3's DQNPolicy takes no share_features_extractor)
    [("DQN", None), *[(a, s) for a in ("SAC", "TD3", "DDPG") for s in (False, True)]],
)
def test_custom_extractor_matches_sb3_on_the_same_weights(algo: str, share: bool | None) -> None:
    kwargs: dict[str, Any] = dict(features_extractor_kwargs=dict(features_dim=8), net_arch=[16])
    if share is not None:
        kwargs["share_features_extractor"] = share
    ours = ALGOS[algo](
        "MlpPolicy",
        ENV_OF[algo],
        **SMALL,
        policy_kwargs={**kwargs, "features_extractor_class": OURS_MLP},
    )
    theirs = getattr(sb3, algo)(
        "MlpPolicy",
        ENV_OF[algo],
        buffer_size=200,
        policy_kwargs={**kwargs, "features_extractor_class": THEIRS_MLP},
    )
    _torch_learner(ours, "the features extractor is TinyMlp")
    obs = _probe(algo)
    obs_t = torch.as_tensor(obs)
    if algo == "DQN":
        _copy_params(theirs.q_net, ours.q_net)
        np.testing.assert_allclose(
            ours.q_net(obs_t).detach().numpy(), theirs.q_net(obs_t).detach().numpy(), atol=1e-6
        )
    else:
        _copy_params(theirs.actor, ours.actor)
        _copy_params(theirs.critic, ours.critic)
        if share:
            assert ours.critic.features_extractor is ours.actor.features_extractor
            assert theirs.critic.features_extractor is theirs.actor.features_extractor
        action = torch.as_tensor(
            np.random.default_rng(2).uniform(-1, 1, (6, 1)), dtype=torch.float32
        )
        with torch.no_grad():
            sb3_q = theirs.critic(obs_t, action)
            for i in range(len(sb3_q)):
                q = ours.critic.q(i, (obs_t, action))
                np.testing.assert_allclose(q.numpy(), sb3_q[i].numpy(), atol=1e-6)
    np.testing.assert_allclose(
        ours.predict(obs, deterministic=True)[0],
        theirs.predict(obs, deterministic=True)[0],
        atol=1e-5,
    )
    ours.learn(24)


@pytest.mark.parametrize("algo", ["SAC", "TD3"])
def test_share_features_extractor_as_sb3(algo: str) -> None:
    """SAC: the critic reads the actor's extractor (trained by the actor only), the target has
    its own, polyak-averaged towards it; TD3: the critic target reads the actor target's."""
    kwargs = dict(features_extractor_class=OURS_MLP, share_features_extractor=True, net_arch=[16])
    model = ALGOS[algo]("MlpPolicy", ENV_OF[algo], seed=0, **SMALL, policy_kwargs=kwargs)
    theirs = getattr(sb3, algo)(
        "MlpPolicy",
        ENV_OF[algo],
        buffer_size=200,
        policy_kwargs={**kwargs, "features_extractor_class": THEIRS_MLP},
    )
    for lib in (model, theirs):
        assert lib.critic.features_extractor is lib.actor.features_extractor
        target_shares = (
            lib.critic_target.features_extractor
            is getattr(lib, "actor_target", lib.critic).features_extractor
        )
        assert target_shares == (algo == "TD3")
    shared = {id(p) for p in model.actor.features_extractor.parameters()}
    critic_group = model.learner.groups["critic"].params
    assert shared and not shared & {id(p) for p in critic_group}
    target = model.critic_target.features_extractor
    before = [p.detach().clone() for p in target.parameters()]
    model.learn(40)
    after = list(model.critic_target.features_extractor.parameters())
    assert all(not torch.equal(a, b) for a, b in zip(before, after))  # it moved
    if algo == "SAC":  # averaged towards the actor's (tau=0.005), not a copy of it
        actor_fe = model.actor.features_extractor.parameters()
        assert all(not torch.equal(a, s) for a, s in zip(after, actor_fe))


@pytest.mark.parametrize("algo", ["DQN", "SAC", "TD3", "DDPG"])
def test_custom_extractor_on_images_and_dicts(algo: str) -> None:
    action = "discrete" if algo == "DQN" else "box"
    cnn = dict(features_extractor_kwargs=dict(features_dim=16), net_arch=[8])
    for policy, obs, kwargs in [
        ("CnnPolicy", "image", cnn),
        ("MultiInputPolicy", "dict", dict(net_arch=[8])),
    ]:
        model = ALGOS[algo](policy, Toy(obs, action), **SMALL, policy_kwargs=kwargs)
        default = NatureCNN if policy == "CnnPolicy" else CombinedExtractor
        net = model.q_net if algo == "DQN" else model.actor
        assert type(net.features_extractor) is default
        model.learn(20)
        assert model.learner.describe().startswith("torch")
        sample = Toy(obs, action).observation_space.sample()
        assert model.predict(sample, deterministic=True)[0] in model.action_space


# -- SB3's tests/test_custom_policy.py, for the off-policy algorithms ----------------------------
@pytest.mark.parametrize(
    ("algo", "net_arch"),
    [
        *[(a, arch) for a in ("DQN", "SAC", "TD3") for arch in ([], [4], [4, 4])],
        *[(a, {"qf": [8], "pi": [8, 4]}) for a in ("SAC", "TD3")],  # DQN's is a list only
    ],
)
def test_flexible_mlp_as_sb3(algo: str, net_arch: Any) -> None:
    """SB3's test_flexible_mlp / test_custom_offpolicy: the same parameter shapes as SB3's."""
    ours = ALGOS[algo]("MlpPolicy", ENV_OF[algo], **SMALL, policy_kwargs=dict(net_arch=net_arch))
    theirs = getattr(sb3, algo)(
        "MlpPolicy", ENV_OF[algo], buffer_size=200, policy_kwargs=dict(net_arch=net_arch)
    )
    mine = [p.shape for n, p in ours.policy.named_parameters() if not n.startswith("ent_coef")]
    assert mine == [p.shape for p in theirs.policy.parameters()]  # SB3: log_ent_coef on the model
    ours.learn(24)


@pytest.mark.parametrize("algo", ["DQN", "SAC", "TD3", "DDPG"])
@pytest.mark.parametrize("optimizer_kwargs", [None, {"weight_decay": 0.0}])
def test_custom_optimizer_as_sb3(algo: str, optimizer_kwargs: Any) -> None:
    """SB3's test_custom_optimizer: AdamW from policy_kwargs, for every part."""
    kwargs = dict(optimizer_class=torch.optim.AdamW, optimizer_kwargs=optimizer_kwargs)
    model = ALGOS[algo](
        "MlpPolicy", ENV_OF[algo], **SMALL, policy_kwargs={**kwargs, "net_arch": [32]}
    )
    # SAC's temperature keeps plain Adam, as in SB3
    groups = {k: g for k, g in model.learner.groups.items() if k != "ent_coef"}
    assert {type(g.optimizer) for g in groups.values()} == {torch.optim.AdamW}
    assert all(
        g.optimizer.defaults["weight_decay"] == (0.0 if optimizer_kwargs else 0.01)
        for g in groups.values()
    )
    model.learn(24)


def test_alias_classes_act_as_their_names() -> None:
    """The ``MlpPolicy`` class gets the name's checks: a Dict observation space asks for
    ``MultiInputPolicy``, as SB3 does; ``CnnPolicy`` the class builds NatureCNN."""
    with pytest.raises(ValueError, match=r"You must use `MultiInputPolicy` .* not MlpPolicy"):
        SAC(sac_module.MlpPolicy, Toy("dict", "box"), buffer_size=100)
    model = TD3(td3_module.CnnPolicy, Toy("image", "box"), **SMALL)
    assert isinstance(model.actor.features_extractor, NatureCNN)
    assert (
        model.learner.describe()
        == "torch learner (numpy cannot: the features extractor is NatureCNN)"
    )


# -- custom policy classes --------------------------------------------------------------------
@pytest.mark.parametrize("algo", ["DQN", "SAC", "TD3", "DDPG"])
def test_custom_policy_class_trains_and_round_trips(tmp_path: Path, algo: str) -> None:
    cls = CUSTOM[algo]
    # NormSACPolicy's own keyword goes into the file and comes back with the class
    own = {"policy_kwargs": {"hidden": 24}} if algo == "SAC" else {}
    model = ALGOS[algo](cls, ENV_OF[algo], seed=0, **SMALL, **own)
    assert isinstance(model.policy, cls)
    _torch_learner(model, f"the policy is a custom {cls.__name__}")
    before = [p.detach().clone() for p in model.policy.parameters()]
    model.learn(48)
    after = list(model.policy.parameters())
    changed = sum(not torch.equal(a, b) for a, b in zip(before, after))
    assert changed >= len(before) // 2, (changed, len(before))
    model.save(tmp_path / "custom")
    with pytest.raises(ModelFileError, match=rf"pass it via custom_objects=\{{'{cls.__name__}'"):
        type(model).load(tmp_path / "custom")
    loaded = type(model).load(
        tmp_path / "custom", env=model.get_env(), custom_objects={cls.__name__: cls}
    )
    assert type(loaded.policy) is cls
    assert loaded.policy_kwargs == model.policy_kwargs
    if algo == "SAC":
        assert loaded.policy.hidden == 24 and loaded.actor.mu.in_features == 24
    obs = _probe(algo)
    np.testing.assert_array_equal(
        model.predict(obs, deterministic=True)[0], loaded.predict(obs, deterministic=True)[0]
    )
    mine, theirs = model.policy.state_dict(), loaded.policy.state_dict()
    assert list(mine) == list(theirs) and all(torch.equal(mine[k], theirs[k]) for k in mine)
    loaded.learn(8)  # and it goes on training


def test_custom_policy_parts_and_keywords() -> None:
    sac = SAC(NormSACPolicy, "Pendulum-v1", **SMALL, policy_kwargs=dict(hidden=24))
    assert isinstance(sac.actor, LayerNormActor) and sac.actor.mu.in_features == 24
    assert [m.out_features for m in sac.critic.qf0 if isinstance(m, nn.Linear)] == [16, 16, 1]
    td3 = TD3(WideCriticTD3Policy, "Pendulum-v1", **SMALL)
    assert [m.out_features for m in td3.critic.qf1 if isinstance(m, nn.Linear)] == [48, 1]
    assert [m.out_features for m in td3.actor.mu if isinstance(m, nn.Linear)] == [400, 300, 1]
    ddpg = DDPG(WideCriticTD3Policy, "Pendulum-v1", **SMALL)
    assert len(ddpg.critic.q_networks) == 1  # DDPG's n_critics=1 reaches a custom policy too
    dqn = DQN(NormDQNPolicy, "CartPole-v1", **SMALL)
    assert isinstance(dqn.q_net, DuelingishQNetwork) and isinstance(dqn.q_net_target, QNetwork)


def test_custom_policy_matches_sb3_custom_policy_shapes() -> None:
    """SB3's guide subclass (net_arch fixed in ``__init__``) over either library's SACPolicy
    builds parameters of the same shapes."""

    def subclass(base: type) -> type:
        class CustomSACPolicy(base):  # type: ignore[misc,valid-type]
            def __init__(self, *args: Any, **kwargs: Any) -> None:
                super().__init__(*args, **kwargs, net_arch=dict(pi=[32], qf=[24, 24]))

        return CustomSACPolicy

    ours = SAC(subclass(SACPolicy), "Pendulum-v1", **SMALL)
    theirs = sb3.SAC(subclass(sb3.sac.policies.SACPolicy), "Pendulum-v1", buffer_size=200)
    for part in ("actor", "critic", "critic_target"):
        mine = [tuple(p.shape) for p in getattr(ours.policy, part).parameters()]
        sb3s = [tuple(p.shape) for p in getattr(theirs.policy, part).parameters()]
        assert mine == sb3s, part
    ours.learn(24)


# -- errors -----------------------------------------------------------------------------------
@pytest.mark.parametrize(
    ("algo", "policy", "base"),
    [
        ("DQN", SACPolicy, "DQNPolicy"),
        ("SAC", TD3Policy, "SACPolicy"),
        ("TD3", SACPolicy, "TD3Policy"),
        ("DDPG", DQNPolicy, "TD3Policy"),
        ("SAC", nn.Linear, "SACPolicy"),
    ],
)
def test_a_policy_class_of_the_wrong_kind(algo: str, policy: type, base: str) -> None:
    with pytest.raises(
        ValueError,
        match=rf"{algo} takes a policy name or a {base} subclass \('MlpPolicy', 'CnnPolicy', "
        rf"'MultiInputPolicy'\), got the class {policy.__name__} from {policy.__module__}",
    ):
        ALGOS[algo](policy, ENV_OF[algo], buffer_size=100)


def test_bad_policy_names_and_keywords() -> None:
    with pytest.raises(ValueError, match=r"Policy 'SACPolicy' unknown: use one of 'MlpPolicy'"):
        SAC("SACPolicy", "Pendulum-v1")
    with pytest.raises(
        TypeError, match=r"DQN policy_kwargs got unexpected keys \['n_critics'\] \(DQNPolicy takes"
    ):
        DQN("MlpPolicy", "CartPole-v1", buffer_size=100, policy_kwargs={"n_critics": 2})
    # A class taking **kwargs passes them on: Python names the one its parent does not take.
    with pytest.raises(
        TypeError, match=r"SACPolicy.__init__\(\) got an unexpected keyword .*'hiden'"
    ):
        SAC(NormSACPolicy, "Pendulum-v1", buffer_size=100, policy_kwargs={"hiden": 2})
    with pytest.raises(TypeError, match=r"unexpected keys \['hidden'\] \(TD3Policy takes "):
        TD3(TD3Policy, "Pendulum-v1", buffer_size=100, policy_kwargs={"hidden": 2})
    with pytest.raises(ValueError, match="policy_kwargs use_sde=True contradicts use_sde=False"):
        SAC("MlpPolicy", "Pendulum-v1", buffer_size=100, policy_kwargs={"use_sde": True})


def test_parts_of_the_wrong_kind() -> None:
    class NoActor(SACPolicy):
        def make_actor(self, features_extractor: Any = None) -> Any:
            return nn.Linear(3, 1)

    with pytest.raises(
        TypeError,
        match=r"NoActor.actor must be a palaestra.algos.common.continuous_policies."
        r"SquashedGaussianActor \(or a subclass; see make_actor/make_critic\), got Linear",
    ):
        SAC(NoActor, "Pendulum-v1", buffer_size=100)

    class SacActorInTd3(TD3Policy):
        def make_actor(self, features_extractor: Any = None) -> Any:
            return SquashedGaussianActor(
                self.observation_space,
                self.action_dim,
                self.make_features_extractor(),
                [8],
                nn.ReLU,
            )

    with pytest.raises(TypeError, match=r"actor must be a .*DeterministicActor .* got Squashed"):
        TD3(SacActorInTd3, "Pendulum-v1", buffer_size=100)
    assert DeterministicActor.__module__ == "palaestra.algos.common.continuous_policies"

    class NoQNet(DQNPolicy):
        def make_q_net(self) -> Any:
            return None

    with pytest.raises(
        TypeError, match=r"NoQNet.q_net must be a torch.nn.Module mapping observations to Q-values"
    ):
        DQN(NoQNet, "CartPole-v1", buffer_size=100)


@pytest.mark.parametrize("algo", ["DQN", "SAC", "TD3", "DDPG"])
def test_a_features_extractor_class_of_the_wrong_kind(algo: str) -> None:
    with pytest.raises(
        TypeError,
        match=r"features_extractor_class must be a BaseFeaturesExtractor subclass "
        r"\(palaestra.algos.networks\), got 'FlattenExtractor'",
    ):
        ALGOS[algo](
            "MlpPolicy",
            ENV_OF[algo],
            buffer_size=100,
            policy_kwargs={"features_extractor_class": "FlattenExtractor"},
        )
    with pytest.raises(
        TypeError,
        match=r"features_extractor_class Flatten built an extractor whose features_dim is None; "
        r"expected a BaseFeaturesExtractor subclass",
    ):
        ALGOS[algo](
            "MlpPolicy",
            ENV_OF[algo],
            buffer_size=100,
            policy_kwargs={"features_extractor_class": nn.Flatten},
        )
