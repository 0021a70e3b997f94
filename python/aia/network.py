"""I-GBNet in PyTorch, the same network as the C++ one (docs/learning.md,
Network), and aia's model file both ways: `load_model` reads a model the
C++ side saved (`aia train`), `save_model` writes one that the C++ igbnet
policy loads (`policy.model`). Needs torch (Debian's python3-torch, CPU; a
GPU when one is there); `import aia` does not import it.

The file is a TorchScript archive whose attributes are the network's
parameters and buffers, plus the buffer `aia_meta`: the network
configuration as JSON (width, hidden, pool, stem_stride, message_hops,
centre and the channel settings: frame, cell, window, blur, cutoff,
geodesic, ...).
"""
import json

import torch
from torch import nn

FORMAT = "aia-igbnet"
# The metadata keys of a model without message passing (format version 2);
# with it, version 3 adds message_hops; version 5 adds centre; version 6
# reach_detour; version 7 reach_broad; version 8 reach_second; version 9
# neighbour_cap.
NETWORK_KEYS = ("width", "hidden", "pool", "stem_stride")
CHANNEL_KEYS = ("frame", "cell", "window", "blur", "cutoff", "geodesic",
                "geodesic_length", "observe_range")
# Channel settings written only when they differ from the default.
OPTIONAL_KEYS = {"reach_margin": 0, "reach_world": False, "search": False,
                 "reach_detour": 0.0, "trail": False, "reach_broad": 0.0,
                 "reach_second": False, "neighbour_cap": 0}


def default_meta(**changes):
    """The metadata of a network: the C++ defaults of aia train (docs/
    learning.md) with `changes`."""
    meta = {"width": 32, "hidden": 128, "pool": 5, "stem_stride": 2,
            "frame": "centred", "cell": 0.5, "window": 40, "blur": 1.0,
            "cutoff": 4.0, "geodesic": False, "geodesic_length": 5.0,
            "observe_range": 2.0}
    for k, v in changes.items():
        if (k not in meta and k not in OPTIONAL_KEYS
                and k not in ("message_hops", "centre")):
            raise KeyError(f"{k}: not a network or channel setting")
        meta[k] = v
    return meta


def channel_params(meta):
    """The channel settings of `meta`, as Mission.channels and Dataset take
    them. A model file leaves out the settings of a channel it does not
    have (the geodesic ones of a four-channel model): their defaults."""
    defaults = default_meta()
    out = {k: meta.get(k, defaults[k]) for k in CHANNEL_KEYS}
    for k, default in OPTIONAL_KEYS.items():
        if meta.get(k, default) != default:
            out[k] = meta[k]
    return out


def num_channels(meta):
    return (4 + (1 if meta.get("geodesic") else 0) + (1 if meta.get("trail") else 0)
            + (1 if float(meta.get("reach_broad", 0.0)) > 0.0 else 0)
            + (1 if meta.get("reach_second") else 0))


def centre_start(meta):
    """The first row and column of the centre (NetworkConfig::CentreStart):
    the robot's cell of the blocks' output minus centre // 2."""
    s = meta["stem_stride"]
    return (meta["window"] // 2 + s // 2) // s - meta.get("centre", 0) // 2


class Block(nn.Module):
    def __init__(self, w):
        super().__init__()
        self.conv1 = nn.Conv2d(w, w, 3, padding=1, bias=False)
        self.bn1 = nn.BatchNorm2d(w)
        self.conv2 = nn.Conv2d(w, w, 3, padding=1, bias=False)
        self.bn2 = nn.BatchNorm2d(w)

    def forward(self, x):
        y = torch.relu(self.bn1(self.conv1(x)))
        return torch.relu(self.bn2(self.conv2(y)) + x)


class IgbNet(nn.Module):
    """Logits of the four moves from a robot's channels."""

    def __init__(self, meta):
        super().__init__()
        w, p, hidden = meta["width"], meta["pool"], meta["hidden"]
        self.meta = dict(meta)
        self.stem = nn.Conv2d(num_channels(meta), w, 3,
                              stride=meta["stem_stride"], padding=1, bias=False)
        self.stem_bn = nn.BatchNorm2d(w)
        self.blocks = nn.ModuleList([Block(w) for _ in range(3)])
        self.pool = nn.AdaptiveAvgPool2d(p)
        # The centre: fc1 also reads the C x C cells around the robot.
        self.centre = meta.get("centre", 0)
        self.centre_start = centre_start(meta)
        self.fc1 = nn.Linear(w * (p * p + self.centre ** 2), hidden)
        self.fc2 = nn.Linear(hidden, 4)
        self.hops = meta.get("message_hops", 0)
        for k in range(1, self.hops + 1):  # message passing: M_1..M_K
            setattr(self, "message%d" % k, nn.Linear(hidden, hidden,
                                                     bias=False))

    def features(self, x):
        """What fc1 reads from a batch of images: the blocks' output pooled
        to a grid, and the centre's cells where the network has one."""
        x = torch.relu(self.stem_bn(self.stem(x)))
        for b in self.blocks:
            x = b(x)
        features = self.pool(x).flatten(1)
        if self.centre:
            c, s = self.centre, self.centre_start
            features = torch.cat(
                [features, x[:, :, s:s + c, s:s + c].flatten(1)], 1)
        return features

    def forward(self, x, neighbours=None):
        """Logits of a batch of robots; `neighbours[b]` lists the rows
        robot b hears (message passing; None: each robot alone)."""
        z = torch.relu(self.fc1(self.features(x)))
        if self.hops == 0 or neighbours is None:
            return self.fc2(z)
        h, hop = z, z
        for k in range(1, self.hops + 1):
            hop = torch.stack([hop[n].mean(0) if n else torch.zeros_like(hop[0])
                               for n in neighbours])
            h = h + getattr(self, "message%d" % k)(hop)
        return self.fc2(torch.relu(h))


def load_model(path, map_location="cpu"):
    """A saved model as an IgbNet in evaluation mode, and its metadata
    (with "channels", the number of input channels, added)."""
    state = torch.jit.load(str(path), map_location=map_location).state_dict()
    meta = json.loads(bytes(state.pop("aia_meta").tolist()).decode())
    meta["channels"] = num_channels(meta)
    net = IgbNet(meta)
    net.load_state_dict(state)
    net.eval()
    return net, meta


class _Archive(nn.Module):
    """What the C++ side reads: the network's parameters and buffers by
    name, and aia_meta."""

    def __init__(self, net, meta_json):
        super().__init__()
        for name, child in net.named_children():
            setattr(self, name, child)
        self.register_buffer("aia_meta", torch.tensor(
            list(meta_json.encode()), dtype=torch.uint8))

    def forward(self, x):
        return x


def save_model(net, path):
    """Writes `net` (an IgbNet) as a model file the C++ igbnet policy loads
    (`policy.model=PATH`): the metadata as aia train writes it
    (NetworkConfig::ToJson), a feature that is off left out so that the
    file keeps the oldest version that has what it uses."""
    meta = default_meta()
    meta.update({k: v for k, v in net.meta.items() if k != "channels"})
    hops = int(meta.pop("message_hops", 0))
    centre = int(meta.pop("centre", 0))
    geodesic = bool(meta["geodesic"])
    world = geodesic and bool(meta.get("reach_world", False))
    out = {k: meta[k] for k in NETWORK_KEYS + CHANNEL_KEYS}
    for k, default in OPTIONAL_KEYS.items():
        if meta.get(k, default) != default:
            out[k] = meta[k]
    if not geodesic:
        for k in ("geodesic", "geodesic_length", "observe_range",
                  "reach_margin"):
            out.pop(k, None)
    if not world:
        for k in ("reach_world", "search", "reach_detour", "reach_broad",
                  "reach_second"):
            out.pop(k, None)
    detour = float(out.get("reach_detour", 0.0)) > 0.0
    broad = float(out.get("reach_broad", 0.0)) > 0.0
    second = bool(out.get("reach_second", False))
    trail = bool(out.get("trail", False))
    out["format"] = FORMAT
    cap = int(out.get("neighbour_cap", 0)) > 0
    out["version"] = (9 if cap else 8 if second else 7 if broad else
                      6 if detour else
                      5 if centre else 4 if world or trail else
                      3 if hops else 2 if geodesic else 1)
    if hops:
        out["message_hops"] = hops
    if centre:
        out["centre"] = centre
    for k in ("cell", "blur", "cutoff", "geodesic_length", "observe_range",
              "reach_detour", "reach_broad"):
        if k in out:
            out[k] = float(out[k])
    text = json.dumps(out, sort_keys=True, separators=(",", ":"))
    archive = _Archive(net.cpu().eval(), text)
    torch.jit.save(torch.jit.script(archive), str(path))
