"""aia.Dataset and a training round trip between PyTorch and the C++
igbnet policy, both ways."""

import glob
import json
import math
import os
import sqlite3
import struct
import subprocess
from pathlib import Path

import numpy as np
import pytest

import aia

torch = pytest.importorskip("torch")
from aia import network  # noqa: E402  (needs torch)

SOURCE = Path(os.environ.get("AIA_SOURCE_DIR", Path(__file__).parents[2]))
BINARY = os.environ.get("AIA_BINARY", str(SOURCE / "build" / "aia"))
DEFAULT = str(SOURCE / "scenarios" / "default.yaml")
# The network's moves alone (docs/python.md, What policy.coordination does
# to a model trained in Python): nothing hand-written chooses or changes a
# move or the channels.
ARGMAX = {"coordination": "none"}


@pytest.fixture(scope="module")
def data(tmp_path_factory):
    out = tmp_path_factory.mktemp("data")
    r = subprocess.run([BINARY, "dataset", "--episodes", "12", "--size",
                        "3x3", "--keep", "5", "--out", str(out), "--quiet"],
                       capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    return out


def test_the_dataset_reads_and_renders_the_shards(data):
    d = aia.Dataset(data)
    assert len(d) == 12 * 5 * 3 and d.num_worlds == 12
    assert set(np.unique(d.labels)) <= {0, 1, 2, 3}
    train, val = d.split(val_share=0.5, seed=3)
    assert len(train) + len(val) == len(d) and len(val) > 0
    # Split by world, as aia train splits.
    assert not set(d.world[train]) & set(d.world[val])
    images, labels = d.batch([0, 5, 7])
    assert images.shape == (3, 4, 40, 40) and images.dtype == np.float32
    assert (labels == d.labels[[0, 5, 7]]).all()
    assert aia.Dataset(data, geodesic=True).batch([0])[0].shape[1] == 5
    with pytest.raises(aia.InputError, match=r"aia.Dataset.batch: "
                       r"indices\[0\]: must be a sample index in \[0, "):
        d.batch([len(d)])
    with pytest.raises(aia.InputError, match=r"indices\[0\]: .*got 1.5"):
        d.batch([1.5])
    with pytest.raises(aia.InputError, match=r"indices: must be integers"):
        d.batch(np.array([1.0]))
    with pytest.raises(aia.InputError, match=r"got True \(bool\)"):
        d.batch([True])
    with pytest.raises(aia.InputError, match=r"no sample indices"):
        d.batch([])
    with pytest.raises(aia.InputError, match=r"val_share: must be a number "
                       r"in \[0, 1\]"):
        d.split(val_share=2)
    assert len(d.batch(np.array([0, 1], dtype=np.int32))[1]) == 2
    with pytest.raises(aia.InputError, match="channels: window"):
        aia.Dataset(data, window=1)


def python_moves(net, meta, mission):
    """The most probable valid move of each robot by the Python network."""
    x = torch.from_numpy(mission.channels(**network.channel_params(meta)))
    with torch.no_grad():
        logits = net(x).numpy()
    logits[~mission.valid_moves()] = -np.inf
    return logits


def check_same_moves(net, meta, model_path, seed, steps=4, scenario=DEFAULT,
                     overrides=None):
    m = aia.Mission(scenario, seed=seed, overrides=overrides)
    cpp = aia.builtin_policy("igbnet", model=str(model_path), **ARGMAX)
    checked = 0
    for _ in range(steps):
        logits = python_moves(net, meta, m)
        moves = cpp.decide(m)
        for i in range(m.num_robots):
            # The C++ move is the Python network's best (to float rounding).
            assert logits[i, moves[i]] >= logits[i].max() - 1e-4, (i, logits[i])
            checked += 1
        m.step(moves)
    return checked


def test_a_model_trained_in_python_runs_in_the_cpp_policy(data, tmp_path):
    torch.manual_seed(0)
    meta = network.default_meta(width=8, hidden=16)
    d = aia.Dataset(data, **network.channel_params(meta))
    net = network.IgbNet(meta)
    opt = torch.optim.Adam(net.parameters(), lr=1e-2)
    for b in range(0, len(d), 30):
        images, labels = d.batch(np.arange(b, min(b + 30, len(d))))
        loss = torch.nn.functional.cross_entropy(
            net(torch.from_numpy(images)), torch.from_numpy(labels))
        opt.zero_grad()
        loss.backward()
        opt.step()
    net.eval()
    path = tmp_path / "py.pt"
    network.save_model(net, path)
    # aia's own reader takes it (policies list it, eval scores it).
    assert check_same_moves(net, meta, path, seed=4) == 40
    back, meta_back = network.load_model(path)
    x = torch.rand(2, 4, 40, 40)
    assert torch.equal(back(x), net(x))
    r = subprocess.run([BINARY, "run", DEFAULT, "--set",
                        f"policy.model={path}", "--max-steps", "3", "--out",
                        str(tmp_path / "run"), "--quiet"],
                       capture_output=True, text=True)
    assert r.returncode == 0, r.stderr


@pytest.mark.parametrize("name", ["igbnet.pt", "igbnet_10x10.pt",
                                  "igbnet_learned.pt"])
def test_a_shipped_model_saved_again_keeps_its_metadata(tmp_path, name):
    """save_model writes what aia train wrote: the same metadata, version
    included (it read keys a model without the reach channel does not have,
    and wrote version 2 for a model of version 4)."""
    original = SOURCE / "models" / name
    net, _ = network.load_model(original)
    copy = tmp_path / name
    network.save_model(net, copy)

    def metadata(path):
        state = torch.jit.load(str(path), map_location="cpu").state_dict()
        return json.loads(bytes(state["aia_meta"].tolist()).decode())
    assert metadata(copy) == metadata(original)


def test_a_centre_network_reads_the_cells_around_the_robot(tmp_path):
    """The centre: fc1 also reads the 3 x 3 cells of the blocks' output
    around the robot's. In the 40-pixel window the robot is pixel 20, which
    the stride-2 stem centres in cell 10: the centre is cells 9..11. With
    its weights at zero the network is the one without it; the C++ policy
    reads a centre model written here and makes its moves."""
    assert network.centre_start(network.default_meta(centre=3)) == 9
    one = network.default_meta(centre=1, stem_stride=1)
    assert network.centre_start(one) == 20
    torch.manual_seed(1)
    plain = network.IgbNet(network.default_meta(width=8, hidden=16)).eval()
    meta = network.default_meta(width=8, hidden=16, centre=3)
    net = network.IgbNet(meta).eval()
    state = plain.state_dict()
    w = torch.zeros_like(net.fc1.weight)
    w[:, :state["fc1.weight"].shape[1]] = state["fc1.weight"]
    state["fc1.weight"] = w
    net.load_state_dict(state)
    x = torch.rand(3, 4, 40, 40)
    with torch.no_grad():
        assert torch.equal(net(x), plain(x))
        net.fc1.weight.normal_(0, 0.3)
        # A pixel beside the robot reaches the logits through the centre
        # alone when the pooled grid's weights are zero.
        net.fc1.weight[:, :8 * 25] = 0
        beside = x.clone()
        beside[:, 0, 20, 22] += 1
        far = x.clone()
        far[:, 0, 2, 2] += 1
        assert not torch.equal(net(beside), net(x))
        assert torch.equal(net(far), net(x))
        net.fc1.weight.normal_(0, 0.3)
    path = tmp_path / "centre.pt"
    network.save_model(net, path)
    back, meta_back = network.load_model(path)
    assert meta_back["centre"] == 3
    assert torch.equal(back(x), net(x))
    assert check_same_moves(net, meta, path, seed=4) == 40


def test_a_broad_reach_model_written_here_runs_in_the_cpp_policy(tmp_path):
    """The broad reach channel (reach_broad, format 7): the seventh input
    after reach, search points and trail; the C++ policy reads a model
    written here, renders the same channels and makes its moves."""
    meta = network.default_meta(width=8, hidden=16, geodesic=True,
                                 geodesic_length=0.25, reach_world=True,
                                 search=True, trail=True, reach_detour=0.5,
                                 reach_broad=5.0)
    assert network.num_channels(meta) == 7
    torch.manual_seed(2)
    net = network.IgbNet(meta).eval()
    path = tmp_path / "broad.pt"
    network.save_model(net, path)
    back, meta_back = network.load_model(path)
    assert meta_back["reach_broad"] == 5.0
    x = torch.rand(2, 7, 40, 40)
    with torch.no_grad():
        assert torch.equal(back(x), net(x))
    m = aia.Mission(DEFAULT, seed=5)
    images = m.channels(**network.channel_params(meta))
    assert images.shape[1] == 7
    plain = m.channels(**{**network.channel_params(meta), "geodesic_length": 5.0,
                          "reach_detour": 0.0, "reach_broad": 0.0})
    # The last channel is channel 4 at L = 5 m, the robots' own images.
    assert np.array_equal(images[:, 6], plain[:, 4])
    assert check_same_moves(net, meta, path, seed=5) == 40


def test_a_capped_neighbours_model_written_here_runs_in_the_cpp_policy(tmp_path):
    """The neighbours channel's cap (neighbour_cap, format 9): a model
    written here with it reads the neighbours channel at most 1 a pixel
    in the C++ policy as in Python, where a team of 30 folds several
    neighbours onto one border pixel."""
    meta = network.default_meta(width=8, hidden=16, neighbour_cap=1)
    torch.manual_seed(4)
    net = network.IgbNet(meta).eval()
    path = tmp_path / "capped.pt"
    network.save_model(net, path)
    _, meta_back = network.load_model(path)
    assert meta_back["neighbour_cap"] == 1 and meta_back["version"] == 9
    crowd = {"robots.count": 30, "targets.count": 6}
    m = aia.Mission(DEFAULT, seed=7, overrides=crowd)
    images = m.channels(**network.channel_params(meta))
    counts = m.channels(**{**network.channel_params(meta),
                           "neighbour_cap": 0})
    assert images[:, 2].max() == 1.0 and counts[:, 2].max() > 1.0
    assert np.array_equal(images[:, 2], np.minimum(counts[:, 2], 1.0))
    assert check_same_moves(net, meta, path, seed=7, overrides=crowd) == 120


def test_a_second_reach_model_written_here_runs_in_the_cpp_policy(tmp_path):
    """The second reach channel (reach_second, format 8): the seventh input
    after reach, search points and trail; the C++ policy reads a model
    written here, renders the same channels and makes its moves."""
    meta = network.default_meta(width=8, hidden=16, geodesic=True,
                                 geodesic_length=0.25, reach_world=True,
                                 search=True, trail=True, reach_detour=0.5,
                                 reach_second=True)
    assert network.num_channels(meta) == 7
    torch.manual_seed(3)
    net = network.IgbNet(meta).eval()
    path = tmp_path / "second.pt"
    network.save_model(net, path)
    back, meta_back = network.load_model(path)
    assert meta_back["reach_second"] is True and meta_back["version"] == 8
    m = aia.Mission(DEFAULT, seed=6)
    images = m.channels(**network.channel_params(meta))
    plain = m.channels(**{**network.channel_params(meta),
                          "reach_second": False})
    assert images.shape[1] == 7
    assert np.array_equal(images[:, :6], plain)
    # Another target's way: lit somewhere, and not channel 4 everywhere.
    assert images[:, 6].max() > 0.0
    assert not np.array_equal(images[:, 6], images[:, 4])
    assert check_same_moves(net, meta, path, seed=6) == 40


def test_the_cpp_model_runs_in_python():
    path = SOURCE / "models" / "igbnet.pt"
    net, meta = network.load_model(path)
    assert meta["channels"] == 5
    assert check_same_moves(net, meta, path, seed=6) == 40


def test_the_learned_model_runs_in_python():
    """The model for coordination none reads the trail (the point each robot
    came from), its search points (where it and its neighbours missed) and
    the reach channel dimmed by the detour: Mission.channels renders them,
    as the policy does, step after step."""
    path = SOURCE / "models" / "igbnet_learned.pt"
    net, meta = network.load_model(path)
    assert meta["channels"] == 6 and meta["trail"] and meta["search"]
    # Seed 2: a robot misses a target from step 1 on, so the search points
    # change the reach channel.
    assert check_same_moves(net, meta, path, seed=2, steps=12) == 120
    # In a world of another lattice step and a shorter sensor the channels
    # are read as the policy reads them: one pixel per step, observation
    # pixels within the sensor's range.
    assert check_same_moves(net, meta, path, seed=2, steps=8, overrides={
        "robots.step": 1.0, "robots.radius": 0.3,
        "sensor.range": 0.5}) == 80
    params = network.channel_params(meta)
    m = aia.Mission(DEFAULT, seed=2)
    m.channels(**params)
    m.step(aia.builtin_policy("igbnet", model=str(path), **ARGMAX).decide(m))
    assert not np.array_equal(m.channels(**params),
                              m.channels(**{**params, "search": False}))
    assert m.channels(**params)[:, 5].sum() > 0  # the trail
    # The reach channel dimmed by the detour from each robot: darker
    # behind the boxes, nowhere brighter.
    assert meta["reach_detour"] > 0
    dimmed = m.channels(**params)[:, 4]
    plain = m.channels(**{**params, "reach_detour": 0.0})[:, 4]
    assert (dimmed <= plain).all() and (dimmed < plain).any()
    # Made of every step's misses: asked for late, refused.
    late = aia.Mission(DEFAULT, seed=2)
    late.step([0] * late.num_robots)
    with pytest.raises(aia.InputError, match=r"aia.Mission.channels: search: "
                       r"the search points are made of every step's misses"):
        late.channels(**params)


def test_a_four_channel_model_file_gives_its_channel_settings(data):
    """A model without the reach channel (version 1: models/igbnet_10x10.pt,
    or `aia train` without --geodesic) leaves its settings out of the file;
    its channel settings are still whole and render its four channels."""
    net, meta = network.load_model(SOURCE / "models" / "igbnet_10x10.pt")
    assert "geodesic" not in meta
    params = network.channel_params(meta)
    assert params["geodesic"] is False
    images, _ = aia.Dataset(data, **params).batch([0, 1])
    assert images.shape == (2, 4, 40, 40)
    assert net(torch.from_numpy(images)).shape == (2, 4)


def test_aia_train_scores_the_choice_among_the_valid_moves(data, tmp_path):
    """`aia train --valid-moves 1`: the loss is the cross-entropy among the
    moves valid from the robot's lattice point (Dataset.valid), the moves
    the policy chooses among. Its validation loss is the one computed here
    from the model's logits with the invalid moves left out, and below the
    loss over all four moves (`--validate` without the flag)."""
    d = aia.Dataset(data)
    assert d.valid.shape == (len(d), 4) and d.valid.dtype == bool
    # The expert moves along the lattice; a robot by a box, a wall or the
    # border has fewer than four moves.
    assert d.valid[np.arange(len(d)), d.labels].all()
    assert (d.valid.sum(1) < 4).any()
    out = tmp_path / "v.pt"
    common = ["--data", str(data), "--val-share", "0.5", "--seed", "3",
              "--valid-moves", "1"]
    r = subprocess.run([BINARY, "train", *common, "--epochs", "1", "--width",
                        "8", "--hidden", "16", "--out", str(out), "--quiet"],
                       capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    log = (tmp_path / "v.train.csv").read_text().splitlines()
    row = dict(zip(log[0].split(","), log[-1].split(",")))
    net, meta = network.load_model(out)
    d = aia.Dataset(data, **network.channel_params(meta))
    _, val = d.split(val_share=0.5, seed=3)
    images, labels = d.batch(val)
    with torch.no_grad():
        logits = net(torch.from_numpy(images))
    mask = torch.from_numpy(d.valid[val])
    among = torch.nn.functional.cross_entropy(
        logits.masked_fill(~mask, -1e9), torch.from_numpy(labels)).item()
    every = torch.nn.functional.cross_entropy(
        logits, torch.from_numpy(labels)).item()
    assert float(row["val_loss"]) == pytest.approx(among, rel=1e-4)
    assert every > among
    r = subprocess.run([BINARY, "train", "--validate", str(out),
                        *common[:-2]], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    assert f"loss {every:.4f}" in r.stdout, (r.stdout, every)


def _assert_weighted_mean(data, tmp_path, flag, chosen, total):
    """At a learning rate too small to move the weights, an epoch's training
    loss is the weighted mean of the same per-sample losses: the means at
    `flag` W = 0 (the samples not chosen) and W = 1 (all) give the mean at
    W = 3, where the `chosen` of `total` samples weigh 3."""
    def train_loss(weight):
        out = tmp_path / f"w{weight}.pt"
        r = subprocess.run([BINARY, "train", "--data", str(data), "--val-share",
                            "0", "--weak-weight", "1", "--lr", "1e-9",
                            "--lr-min", "1e-9", "--epochs", "1", "--width", "8",
                            "--hidden", "16", flag, str(weight),
                            "--out", str(out), "--quiet"],
                           capture_output=True, text=True)
        assert r.returncode == 0, r.stderr
        log = (tmp_path / f"w{weight}.train.csv").read_text().splitlines()
        return float(dict(zip(log[0].split(","),
                              log[-1].split(",")))["train_loss"])

    assert 0 < chosen < total
    others = total - chosen
    l0, l1, l3 = train_loss(0), train_loss(1), train_loss(3)
    s_others = l0 * others
    s_chosen = l1 * total - s_others
    assert l3 == pytest.approx((s_others + 3 * s_chosen)
                               / (others + 3 * chosen), rel=1e-3)
    assert abs(l3 - l1) > 1e-3 * l1


def test_aia_train_weighs_the_acting_policys_mistakes(tmp_path):
    """`aia train --mistake-weight W` multiplies the weight of the samples
    whose acting policy's move differs from the expert's label (Dataset.acted
    against Dataset.labels)."""
    data = tmp_path / "greedy"
    r = subprocess.run([BINARY, "dataset", "--episodes", "12", "--size", "3x3",
                        "--keep", "5", "--policy", "greedy", "--out",
                        str(data), "--quiet"], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    d = aia.Dataset(data)
    _assert_weighted_mean(data, tmp_path, "--mistake-weight",
                          int((d.acted != d.labels).sum()), len(d))


def test_aia_train_weighs_a_missions_ending(tmp_path):
    """`aia train --ending-weight W` multiplies the weight of the samples
    whose robot's own belief holds one or two targets above eps (read here
    from the shards themselves: each target's log det Sigma is the sixth
    float64 of its blob, eps the world's)."""
    data = tmp_path / "expert"
    r = subprocess.run([BINARY, "dataset", "--episodes", "12", "--size", "3x3",
                        "--keep", "30", "--out", str(data), "--quiet"],
                       capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    endings = total = 0
    for shard in glob.glob(str(data / "*.sqlite")):
        con = sqlite3.connect(shard)
        eps = dict(con.execute("select episode, eps from worlds"))
        for episode, blob in con.execute("select episode, targets from samples"):
            v = struct.unpack(f"<{len(blob) // 8}d", blob)
            above = sum(1 for x in v[5::6] if x > math.log(eps[episode]))
            endings += 1 <= above <= 2
            total += 1
        con.close()
    assert total == len(aia.Dataset(data))
    _assert_weighted_mean(data, tmp_path, "--ending-weight", endings, total)
