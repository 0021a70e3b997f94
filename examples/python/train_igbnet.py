#!/usr/bin/python3
"""Trains I-GBNet in PyTorch on `aia dataset` data rendered by the C++
renderer, and saves a model that the C++ igbnet policy loads:

    build/aia dataset --episodes 40 --size 5x5 --out renders/data
    PYTHONPATH=build/python examples/python/train_igbnet.py renders/data renders/py.pt
    build/aia eval --sizes 5x5 --seeds 10 --policies igbnet --set policy.model=renders/py.pt --out renders/py_eval

Runs on a GPU when torch sees one. A small network and few epochs by
default (flags below); `aia train` is the shipped recipe.
"""
import argparse

import numpy as np
import torch

import aia
from aia import network


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("data", nargs="+", help="dataset folders or files")
    p.add_argument("out", help="model file to write")
    p.add_argument("--epochs", type=int, default=3)
    p.add_argument("--batch", type=int, default=32)
    p.add_argument("--lr", type=float, default=1e-3)
    p.add_argument("--width", type=int, default=16)
    p.add_argument("--hidden", type=int, default=64)
    p.add_argument("--seed", type=int, default=1)
    args = p.parse_args()

    torch.manual_seed(args.seed)
    device = "cuda" if torch.cuda.is_available() else "cpu"
    meta = network.default_meta(width=args.width, hidden=args.hidden)
    data = aia.Dataset(args.data, **network.channel_params(meta))
    train, val = data.split(val_share=0.1, seed=args.seed)
    net = network.IgbNet(meta).to(device)
    opt = torch.optim.Adam(net.parameters(), lr=args.lr)
    rng = np.random.default_rng(args.seed)
    for epoch in range(1, args.epochs + 1):
        net.train()
        order = rng.permutation(train)
        total = 0.0
        for b in range(0, len(order), args.batch):
            images, labels = data.batch(order[b:b + args.batch])
            x = torch.from_numpy(images).to(device)
            y = torch.from_numpy(labels).to(device)
            loss = torch.nn.functional.cross_entropy(net(x), y)
            opt.zero_grad()
            loss.backward()
            opt.step()
            total += loss.item() * len(y)
        acc = accuracy(net, data, val, device) if len(val) else float("nan")
        print(f"epoch {epoch}: train loss {total / max(len(train), 1):.3f}, "
              f"validation accuracy {acc:.3f} ({len(val)} samples)",
              flush=True)
    network.save_model(net, args.out)
    print(f"wrote {args.out}")


def accuracy(net, data, indices, device):
    net.eval()
    right = 0
    with torch.no_grad():
        for b in range(0, len(indices), 256):
            images, labels = data.batch(indices[b:b + 256])
            logits = net(torch.from_numpy(images).to(device)).cpu().numpy()
            right += int((logits.argmax(axis=1) == labels).sum())
    return right / len(indices)


if __name__ == "__main__":
    main()
