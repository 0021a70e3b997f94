#!/usr/bin/python3
"""Trains I-GBNet in PyTorch on `aia dataset` data rendered by the C++
renderer, and saves a model that the C++ igbnet policy loads:

    build/aia dataset --episodes 40 --size 5x5 --out renders/data
    PYTHONPATH=build/python examples/python/train_igbnet.py renders/data renders/py.pt
    build/aia eval --sizes 5x5 --seeds 10 --policies igbnet --set policy.model=renders/py.pt --out renders/py_eval

On several processes (torch.distributed, DistributedDataParallel: gloo on
CPUs, NCCL on GPUs): `--processes N` starts N here; under `torchrun` or
`srun` each process is one rank (docs/python.md, "Train a network").
Each rank reads its own set of shard files (rank r: the files r, r + N,
... of the sorted list; with fewer files than ranks, every rank reads them
all and takes every N-th training sample), `--batch` is the global batch
(each rank takes batch / N), and the gradients are averaged: the same
training as one process, but for batch norm's statistics (each rank's own).

Runs on a GPU when torch sees one. A small network and few epochs by
default (flags below); `aia train` is the shipped recipe.
"""
import argparse
import gc
import glob
import os
import tempfile

import numpy as np
import torch
import torch.distributed as dist

import aia
from aia import network


def shard_files(paths):
    """Every shard file of `paths` (folders or files), sorted."""
    files = []
    for p in paths:
        if os.path.isdir(p):
            found = sorted(glob.glob(os.path.join(p, "shard-*.sqlite")))
            files += found or [p]  # a folder of another layout: aia decides
        else:
            files.append(p)
    return sorted(set(files), key=files.index)


def launched_rank():
    """(rank, world size, local rank) set by torchrun or srun, or None."""
    env = os.environ
    if "RANK" in env and "WORLD_SIZE" in env:
        return (int(env["RANK"]), int(env["WORLD_SIZE"]),
                int(env.get("LOCAL_RANK", 0)))
    if "SLURM_PROCID" in env and int(env.get("SLURM_NTASKS", "1")) > 1:
        return (int(env["SLURM_PROCID"]), int(env["SLURM_NTASKS"]),
                int(env.get("SLURM_LOCALID", 0)))
    return None


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("data", nargs="+", help="dataset folders or files")
    p.add_argument("out", help="model file to write")
    p.add_argument("--epochs", type=int, default=3)
    p.add_argument("--batch", type=int, default=32,
                   help="global batch (split over the processes)")
    p.add_argument("--lr", type=float, default=1e-3)
    p.add_argument("--width", type=int, default=16)
    p.add_argument("--hidden", type=int, default=64)
    p.add_argument("--seed", type=int, default=1)
    p.add_argument("--processes", type=int, default=1,
                   help="processes to start here (torch.distributed)")
    p.add_argument("--threads", type=int, default=os.cpu_count() or 1,
                   help="CPU threads of all the processes of this machine")
    args = p.parse_args()
    if args.processes < 1:
        p.error("--processes: must be at least 1")
    launched = launched_rank()
    if launched is not None:
        rank, world, local = launched
        os.environ.setdefault("MASTER_PORT", "29500")
        if "MASTER_ADDR" not in os.environ:
            p.error("MASTER_ADDR: set it to the first node's address "
                    "(torchrun does; under srun see docs/python.md)")
        train(rank, world, local, args, "env://",
              int(os.environ.get("LOCAL_WORLD_SIZE", world)))
    elif args.processes > 1:
        with tempfile.TemporaryDirectory() as tmp:
            torch.multiprocessing.spawn(
                spawned, args=(args, "file://" + os.path.join(tmp, "init")),
                nprocs=args.processes)
    else:
        train(0, 1, 0, args, None, 1)


def spawned(rank, args, init):
    train(rank, args.processes, rank, args, init, args.processes)


def train(rank, world, local, args, init, local_world):
    cuda = torch.cuda.is_available()
    device = f"cuda:{local % torch.cuda.device_count()}" if cuda else "cpu"
    torch.set_num_threads(max(1, args.threads // local_world))
    distributed = world > 1
    if distributed:
        dist.init_process_group("nccl" if cuda else "gloo",
                                init_method=init, rank=rank,
                                world_size=world)
    lead = rank == 0
    meta = network.default_meta(width=args.width, hidden=args.hidden)
    files = shard_files(args.data)
    split_files = len(files) >= world
    mine = files[rank::world] if split_files else files
    data = aia.Dataset(mine, **network.channel_params(meta))
    train_idx, val = data.split(val_share=0.1, seed=args.seed)
    if not split_files:
        train_idx, val = train_idx[rank::world], val[rank::world]
    torch.manual_seed(args.seed)  # the same start on every rank
    net = network.IgbNet(meta).to(device)
    model = net
    if distributed:
        model = torch.nn.parallel.DistributedDataParallel(
            net, device_ids=[device] if cuda else None)
    opt = torch.optim.Adam(model.parameters(), lr=args.lr)
    rng = np.random.default_rng(args.seed + rank)
    local_batch = max(1, args.batch // world)
    steps = -(-len(train_idx) // local_batch)
    counts = gathered([len(train_idx), len(val)], distributed, world)
    steps = int(max(reduce_all([steps], distributed, "max")[0], 1))
    if lead:
        where = "shard files" if split_files else "every N-th sample"
        print(f"{world} process{'es' if world > 1 else ''} "
              f"({'nccl' if cuda else 'gloo'} backend) "
              f"by {where}: training samples per rank "
              f"{[c[0] for c in counts]}, {steps} steps an epoch",
              flush=True)
    for epoch in range(1, args.epochs + 1):
        model.train()
        order = rng.permutation(train_idx)
        # Every rank takes the same number of steps (DDP averages each
        # step over all): a rank with fewer samples goes round again.
        order = np.resize(order, steps * local_batch) if len(order) else order
        total = np.zeros(2)
        for b in range(steps):
            chunk = order[b * local_batch:(b + 1) * local_batch]
            images, labels = data.batch(chunk)
            x = torch.from_numpy(images).to(device)
            y = torch.from_numpy(labels).to(device)
            loss = torch.nn.functional.cross_entropy(model(x), y)
            opt.zero_grad()
            loss.backward()
            opt.step()
            total += [loss.item() * len(y), len(y)]
        total = reduce_all(total, distributed, "sum")
        right, seen = reduce_all(accuracy(net, data, val, device),
                                 distributed, "sum")
        acc = right / seen if seen else float("nan")
        if lead:
            print(f"epoch {epoch}: train loss {total[0] / max(total[1], 1):.3f}"
                  f", validation accuracy {acc:.3f} ({int(seen)} samples)",
                  flush=True)
    if distributed:
        # DDP keeps the ranks' weights equal; say so, as a check.
        sums = gathered([float(sum(t.double().sum() for t in
                                   net.parameters()))], distributed, world)
        if lead:
            agree = all(s == sums[0] for s in sums)
            print(f"ranks agree on the weights: {agree}", flush=True)
    if lead:
        network.save_model(net, args.out)
        print(f"wrote {args.out}", flush=True)
    if distributed:
        dist.barrier()
        # Drop DDP's reducer while the group still holds itself: the group's
        # last reference going with the reducer would join gloo's worker
        # threads with the GIL held, and a worker freeing a tensor Python
        # made needs the GIL (a hang at exit, torch 1.13).
        del model
        gc.collect()
        dist.destroy_process_group()


def reduce_all(values, distributed, op):
    t = torch.tensor(np.asarray(values, dtype=np.float64))
    if distributed:
        dist.all_reduce(t, op=dist.ReduceOp.SUM if op == "sum"
                        else dist.ReduceOp.MAX)
    return t.numpy()


def gathered(values, distributed, world):
    t = torch.tensor(np.asarray(values, dtype=np.float64))
    if not distributed:
        return [t.tolist()]
    out = [torch.zeros_like(t) for _ in range(world)]
    dist.all_gather(out, t)
    return [o.tolist() for o in out]


def accuracy(net, data, indices, device):
    """(right, total) of the network's moves on these samples."""
    net.eval()
    right = 0
    with torch.no_grad():
        for b in range(0, len(indices), 256):
            images, labels = data.batch(indices[b:b + 256])
            logits = net(torch.from_numpy(images).to(device)).cpu().numpy()
            right += int((logits.argmax(axis=1) == labels).sum())
    return [right, len(indices)]


if __name__ == "__main__":
    main()
