"""A grid on a Ray cluster of two nodes (simulated on this machine): the same bits as local."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from palaestra.runs import RunSpec
from palaestra.runs.grid import GridRun, run_grid

ray = pytest.importorskip("ray")


@pytest.mark.slow
def test_two_node_cluster_trains_a_grid_like_the_local_backend(tmp_path: Path) -> None:
    from ray.cluster_utils import Cluster

    from palaestra.runs import load_model

    if ray.is_initialized():
        ray.shutdown()
    cluster = Cluster(initialize_head=True, head_node_args={"num_cpus": 1})
    cluster.add_node(num_cpus=1)
    try:
        runs = {
            backend: [
                GridRun("ppo", RunSpec.from_preset("ppo", "CartPole-v1", seed=s, n_timesteps=512),
                        tmp_path / backend / f"seed{s}")
                for s in range(4)
            ]
            for backend in ("local", "ray")
        }  # fmt: skip
        run_grid(runs["local"], "local")
        outcomes = run_grid(runs["ray"], "ray", address=cluster.address)
        assert [o.status for o in outcomes] == ["trained"] * 4
        assert len({n["NodeID"] for n in ray.nodes() if n["Alive"]}) == 2
        for a, b in zip(runs["local"], runs["ray"]):
            ours = load_model(a.run_dir / "model.zip").policy.state_dict()
            theirs = load_model(b.run_dir / "model.zip").policy.state_dict()
            for name, value in ours.items():
                np.testing.assert_array_equal(value.numpy(), theirs[name].numpy())
    finally:
        ray.shutdown()
        cluster.shutdown()
