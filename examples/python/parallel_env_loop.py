#!/usr/bin/python3
"""The PettingZoo ParallelEnv loop: every agent observes its channels and
vector, acts, and gets its reward (docs/python.md). Here each agent imitates
the built-in greedy policy; put your learner's actions in its place.

    PYTHONPATH=build/python examples/python/parallel_env_loop.py
"""
import aia

env = aia.parallel_env("scenarios/default.yaml", seed=2)
observations, infos = env.reset()
teacher = aia.builtin_policy("greedy")
returns = {a: 0.0 for a in env.possible_agents}
while env.agents:
    moves = teacher.decide(env.mission)
    actions = {a: int(moves[env.possible_agents.index(a)]) for a in env.agents}
    observations, rewards, terminations, truncations, infos = env.step(actions)
    for a, r in rewards.items():
        returns[a] += r
print(f"success {env.mission.success} in {env.mission.steps} steps")
print("returns:", {a: round(r, 2) for a, r in returns.items()})
