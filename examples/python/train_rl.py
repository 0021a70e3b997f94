#!/usr/bin/python3
"""Multi-agent PPO on I-GBNet: every robot is an agent with the same
weights (parameter sharing) acting on its own channels, exactly what the
C++ igbnet policy sees; moves off the lattice are masked out; missions of
a small world are stepped together on C++ threads (aia.VectorMissions with
autoreset). The result is a model file the C++ policy loads:

    PYTHONPATH=build/python examples/python/train_rl.py --out renders/rl.pt --minutes 30
    build/aia run scenarios/default.yaml --set policy.model=renders/rl.pt --set policy.coordination=none

`--init models/igbnet.pt` fine-tunes a model (the shipped one: its channel
settings and size are kept); `--quick` is a two-update smoke run for the
tests. docs/python.md ("Fine-tune with RL") has the measured figures.

Reward of a robot at a step: how much of the targets' uncertainty its own
fused belief lost (each target counts 1 from its prior to eps, in log det
Sigma), less `--step-penalty`, plus `--success-bonus` when the mission
succeeds. Success is measured with the network's most probable valid move
(what `policy.coordination=none` runs) on seeds that training never sees.
"""
import argparse
import csv
import json
import os
import sys
import time

import numpy as np
import torch
from torch import nn

import aia
from aia import network

SCENARIO = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..",
                        "scenarios", "default.yaml")
# The small world: 3 robots, 3 targets, 10 x 10 m with 8 random boxes.
SMALL_WORLD = {"workspace.size": [10, 10],
               "workspace.obstacles.random.count": 8,
               "robots.count": 3, "targets.count": 3,
               "mission.max_steps": 60}
TRAIN_SEEDS = 1_000_000  # training missions: seeds from here on
VALIDATION_SEEDS = 500_000  # choosing the model kept
TEST_SEEDS = 0  # the figure reported


class ActorCritic(nn.Module):
    """I-GBNet's layers (the actor, saved as the model) and a value head on
    its hidden features (the critic, dropped when saving)."""

    def __init__(self, net):
        super().__init__()
        self.net = net
        self.value = nn.Linear(net.fc1.out_features, 1)

    def features(self, x):
        return self.net.features(x)

    def head(self, f):
        z = torch.relu(self.net.fc1(f))
        return self.net.fc2(z), self.value(z).squeeze(1)

    def forward(self, x):
        return self.head(self.features(x))


def masked(logits, mask):
    return logits.masked_fill(~mask, -1e9)


def remaining(states, final=None):
    """(missions, robots): how much uncertainty each robot's own belief
    has left, each target from 1 (its prior) to 0 (eps)."""
    log_eps = np.log(states["eps"])[:, None, None]
    prior = states["log_det_prior"][:, None, :]
    with np.errstate(divide="ignore"):
        log_det = np.log(states["det"])
    share = (log_det - log_eps) / np.maximum(prior - log_eps, 1e-9)
    return np.clip(share, 0.0, 1.0).sum(axis=2)


def one_state_remaining(state):
    stacked = {k: np.asarray(state[k])[None] for k in
               ("det", "eps", "log_det_prior")}
    return remaining(stacked)[0]


def observe(vector, params):
    """Channels (missions * robots, C, H, W) and valid-move masks."""
    images = vector.channels(**params)  # rendered on the vector's threads
    images = images.reshape(-1, *images.shape[2:])
    masks = np.concatenate([m.valid_moves() for m in vector.missions])
    return torch.from_numpy(images), torch.from_numpy(masks)


def success_rate(net, params, scenario, overrides, seeds, threads):
    """Share of missions at `seeds` that succeed with the network's most
    probable valid move, and their mean steps."""
    v = aia.VectorMissions(len(seeds), scenario, seed=seeds[0],
                           overrides=overrides, threads=threads)
    robots = v.num_robots
    while not v.done.all():
        x, mask = observe(v, params)
        with torch.no_grad():
            logits = masked(net(x), mask)
        v.step(logits.argmax(1).numpy().reshape(len(seeds), robots))
    steps = [m.steps for m in v.missions]
    return float(np.mean([m.success for m in v.missions])), float(
        np.mean(steps))


def cpp_success_rate(model, scenario, overrides, seeds, coordination):
    """The same missions decided by the C++ igbnet policy with this model."""
    v = aia.VectorMissions(len(seeds), scenario, seed=seeds[0],
                           overrides=overrides)
    policies = [aia.builtin_policy("igbnet", model=str(model),
                                   coordination=coordination)
                for _ in seeds]
    while not v.done.all():
        v.step(np.stack([p.decide(m) for p, m in zip(policies, v.missions)]))
    return float(np.mean([m.success for m in v.missions]))


def parse_sets(items):
    out = dict(SMALL_WORLD)
    for item in items:
        key, sep, value = item.partition("=")
        if not sep:
            sys.exit(f"--set {item}: must be KEY=VALUE")
        out[key] = json.loads(value) if value[:1] in "[{" else value
    return out


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--out", required=True, help="model file to write")
    p.add_argument("--init", help="model to start from (fine-tuning)")
    p.add_argument("--scenario", default=SCENARIO)
    p.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                   help="scenario overrides on top of the small world")
    p.add_argument("--minutes", type=float, default=30.0,
                   help="wall-clock budget (training stops, then the test)")
    p.add_argument("--updates", type=int, default=0, help="0: no limit")
    p.add_argument("--missions", type=int, default=16)
    p.add_argument("--rollout", type=int, default=32)
    p.add_argument("--width", type=int, default=16)
    p.add_argument("--hidden", type=int, default=64)
    p.add_argument("--window", type=int, default=24)
    p.add_argument("--lr", type=float,
                   help="Adam's step (default 5e-4; 1e-4 with --init)")
    p.add_argument("--epochs", type=int, default=3)
    p.add_argument("--minibatch", type=int, default=512)
    p.add_argument("--gamma", type=float, default=0.97)
    p.add_argument("--lam", type=float, default=0.95)
    p.add_argument("--clip", type=float, default=0.2)
    p.add_argument("--entropy", type=float, default=0.01)
    p.add_argument("--step-penalty", type=float, default=0.02)
    p.add_argument("--success-bonus", type=float, default=1.0)
    p.add_argument("--validate-every", type=int, default=10,
                   help="updates between validations (the best is kept)")
    p.add_argument("--validation-seeds", type=int, default=50)
    p.add_argument("--test-seeds", type=int, default=100)
    p.add_argument("--threads", type=int, default=2)
    p.add_argument("--seed", type=int, default=1)
    p.add_argument("--compare", action="store_true",
                   help="also score the test missions with the C++ policy "
                        "on this model (coordination none and rules), the "
                        "shipped model and greedy")
    p.add_argument("--freeze-trunk", action="store_true",
                   help="with --init: train only the MLP and the value head; "
                        "the convolutions' features are computed once per "
                        "rollout step and reused by every epoch (an update "
                        "of the shipped model 1.6 s instead of 47 s here)")
    p.add_argument("--quick", action="store_true",
                   help="a smoke run: 2 small updates, a tiny network")
    args = p.parse_args()
    # The model is written after the training: a --out that cannot be one
    # is refused before it.
    if os.path.isdir(args.out) or not os.path.isdir(
            os.path.dirname(os.path.abspath(args.out))):
        print(f"error: --out: {args.out}: give a model file in an "
              "existing folder", file=sys.stderr)
        sys.exit(2)
    if args.quick:
        args.updates, args.missions, args.rollout = 2, 4, 8
        args.width, args.hidden, args.minibatch = 4, 16, 64
        args.validate_every, args.validation_seeds, args.test_seeds = 0, 2, 2
        args.epochs = 1

    if args.freeze_trunk and not args.init:
        sys.exit("--freeze-trunk: needs --init (a trained trunk to keep)")
    if args.lr is None:
        args.lr = 1e-4 if args.init else 5e-4
    torch.manual_seed(args.seed)
    torch.set_num_threads(args.threads)
    overrides = parse_sets(args.set)
    if args.init:
        net, meta = network.load_model(args.init)
        if meta.get("message_hops", 0):
            sys.exit("--init: a model with message passing is not supported "
                     "here (each robot acts on its own channels)")
        meta.pop("channels", None)
        meta.pop("format", None)
        meta.pop("version", None)
        net.meta = meta
    else:
        meta = network.default_meta(width=args.width, hidden=args.hidden,
                                    window=args.window, geodesic=True)
        net = network.IgbNet(meta)
    params = network.channel_params(meta)
    model = ActorCritic(net)
    # Batch norm as the C++ policy runs it (its running statistics, not
    # the batch's): the moves trained are the moves played.
    model.eval()
    trained = model.parameters()
    if args.freeze_trunk:
        trained = [q for m in (net.fc1, net.fc2, model.value)
                   for q in m.parameters()]
    opt = torch.optim.Adam(trained, lr=args.lr)

    def inputs(x):
        """What the update reads: the images, or the frozen trunk's
        features of them."""
        if not args.freeze_trunk:
            return x
        with torch.no_grad():
            return model.features(x)

    def act(x):
        return model.head(x) if args.freeze_trunk else model(x)
    gen = torch.Generator().manual_seed(args.seed)

    vector = aia.VectorMissions(args.missions, args.scenario,
                                seed=TRAIN_SEEDS + args.seed * 100_000,
                                overrides=overrides, threads=args.threads,
                                autoreset=True)
    n = args.missions * vector.num_robots
    log_path = os.path.splitext(args.out)[0] + ".rl.csv"
    log = open(log_path, "w", newline="")
    writer = csv.writer(log)
    writer.writerow(["update", "seconds", "samples", "episodes",
                     "train_success", "train_steps", "entropy", "approx_kl",
                     "validation_success", "validation_steps"])
    start = time.monotonic()
    budget = args.minutes * 60.0
    validation = [VALIDATION_SEEDS + i for i in range(args.validation_seeds)]
    best = (-1.0, None)
    states = vector.states()
    left = remaining(states)
    update, samples = 0, 0
    while True:
        update += 1
        if args.updates and update > args.updates:
            break
        if time.monotonic() - start > budget:
            break
        obs, masks, actions, logps, values, rewards, dones = \
            [], [], [], [], [], [], []
        ended = []
        for _ in range(args.rollout):
            x, mask = observe(vector, params)
            x = inputs(x)
            with torch.no_grad():
                logits, value = act(x)
                dist = torch.distributions.Categorical(
                    logits=masked(logits, mask))
                a = torch.multinomial(dist.probs, 1, generator=gen)[:, 0]
            result = vector.step(a.numpy().reshape(args.missions, -1))
            states = vector.states()
            after = remaining(states)
            done = np.asarray(result.done)
            if done.any():
                for e in np.flatnonzero(done):
                    after[e] = one_state_remaining(
                        result.info["final_state"][e])
                    ended.append(result.info["final_info"][e])
            r = left - after - args.step_penalty
            r += args.success_bonus * (np.asarray(result.success) &
                                       done)[:, None]
            left = remaining(states)
            obs.append(x)
            masks.append(mask)
            actions.append(a)
            logps.append(dist.log_prob(a))
            values.append(value)
            rewards.append(torch.from_numpy(r.reshape(-1)).float())
            dones.append(torch.from_numpy(
                np.repeat(done, vector.num_robots)).float())
        with torch.no_grad():
            _, last = act(inputs(observe(vector, params)[0]))
        values.append(last)
        # GAE over the rollout, per robot.
        adv = torch.zeros(args.rollout, n)
        gae = torch.zeros(n)
        for t in reversed(range(args.rollout)):
            live = 1.0 - dones[t]
            delta = rewards[t] + args.gamma * values[t + 1] * live - values[t]
            gae = delta + args.gamma * args.lam * live * gae
            adv[t] = gae
        returns = adv + torch.stack(values[:-1])
        flat = dict(obs=torch.cat(obs), mask=torch.cat(masks),
                    action=torch.cat(actions), logp=torch.cat(logps),
                    adv=adv.reshape(-1), ret=returns.reshape(-1))
        flat["adv"] = (flat["adv"] - flat["adv"].mean()) / (
            flat["adv"].std() + 1e-8)
        total = flat["obs"].shape[0]
        samples += total
        entropies, kls = [], []
        for _ in range(args.epochs):
            order = torch.randperm(total, generator=gen)
            for b in range(0, total, args.minibatch):
                idx = order[b:b + args.minibatch]
                logits, value = act(flat["obs"][idx])
                dist = torch.distributions.Categorical(
                    logits=masked(logits, flat["mask"][idx]))
                logp = dist.log_prob(flat["action"][idx])
                ratio = torch.exp(logp - flat["logp"][idx])
                a = flat["adv"][idx]
                policy_loss = -torch.min(
                    ratio * a,
                    torch.clamp(ratio, 1 - args.clip, 1 + args.clip) * a
                ).mean()
                value_loss = ((value - flat["ret"][idx]) ** 2).mean()
                entropy = dist.entropy().mean()
                loss = policy_loss + 0.5 * value_loss - args.entropy * entropy
                opt.zero_grad()
                loss.backward()
                nn.utils.clip_grad_norm_(model.parameters(), 0.5)
                opt.step()
                entropies.append(entropy.item())
                kls.append((flat["logp"][idx] - logp).mean().item())
        v_success = v_steps = ""
        if args.validate_every and update % args.validate_every == 0:
            v_success, v_steps = success_rate(
                net, params, args.scenario, overrides, validation,
                args.threads)
            if v_success > best[0]:
                best = (v_success, {k: t.clone() for k, t in
                                    net.state_dict().items()})
        train_success = np.mean([e["success"] for e in ended]) \
            if ended else float("nan")
        train_steps = np.mean([e["steps"] for e in ended]) \
            if ended else float("nan")
        seconds = time.monotonic() - start
        writer.writerow([update, round(seconds, 1), samples, len(ended),
                         round(float(train_success), 3),
                         round(float(train_steps), 1),
                         round(float(np.mean(entropies)), 3),
                         round(float(np.mean(kls)), 4), v_success, v_steps])
        log.flush()
        print(f"update {update} ({seconds:.0f} s, {samples} samples): "
              f"{len(ended)} missions ended, success {train_success:.2f} "
              f"(sampled moves), steps {train_steps:.1f}, entropy "
              f"{np.mean(entropies):.2f}"
              + (f"; validation success {v_success:.2f}"
                 if v_success != "" else ""), flush=True)
    if args.validate_every:
        v_success, _ = success_rate(net, params, args.scenario, overrides,
                                    validation, args.threads)
        if best[1] is not None and best[0] > v_success:
            net.load_state_dict(best[1])
            print(f"kept the best validated model (success {best[0]:.2f})")
    net.eval()
    network.save_model(net, args.out)
    test = [TEST_SEEDS + i for i in range(args.test_seeds)]
    success, steps = success_rate(net, params, args.scenario, overrides,
                                  test, args.threads)
    print(f"test ({len(test)} missions, seeds {test[0]}..{test[-1]}): "
          f"success {success:.2f}, mean steps {steps:.1f} (the network's "
          f"most probable valid move: policy.coordination=none)")
    if args.compare:
        shipped = os.path.join(os.path.dirname(SCENARIO), "..", "models",
                               "igbnet.pt")
        rows = [("this model, C++ igbnet, coordination none", args.out,
                 "none"),
                ("this model, C++ igbnet, coordination rules", args.out,
                 "rules"),
                ("models/igbnet.pt, coordination none", shipped, "none"),
                ("models/igbnet.pt, coordination rules", shipped, "rules")]
        for label, path, coordination in rows:
            rate = cpp_success_rate(path, args.scenario, overrides, test,
                                    coordination)
            print(f"  {label}: success {rate:.2f}", flush=True)
        v = aia.VectorMissions(len(test), args.scenario, seed=test[0],
                               overrides=overrides)
        greedy = [aia.builtin_policy("greedy") for _ in test]
        while not v.done.all():
            v.step(np.stack([g.decide(m) for g, m in zip(greedy, v.missions)]))
        print(f"  greedy: success "
              f"{np.mean([m.success for m in v.missions]):.2f}", flush=True)
    print(f"wrote {args.out} and {log_path}; "
          f"{time.monotonic() - start:.0f} s", flush=True)
    log.close()


if __name__ == "__main__":
    main()
