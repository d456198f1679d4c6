"""Speed of the off-policy stack against bare PyTorch/MuJoCo loops doing the same work, in one run.

    python scripts/benchmarks/bench_collect.py [--frames 20000] [--updates 300] [--repeats 3] \
        [actor=mlp ...]
    python scripts/benchmarks/bench_collect.py --ray HEAD:6379 [--collectors 2]   # and RayCollector

1. One DDPG update (the ``ddpg`` loss: TorchRL's ``DDPGLoss`` + ``SoftUpdate``) against a bare
   PyTorch update of the same networks on the same batch (TD(0) target from target networks, L2
   critic loss, actor loss -Q(s, μ(s)), both Adams, the same gradient clipping, soft target update).
   Target: ours within 1.2x of bare.
2. Collection: env steps/s of the TorchRL ``Collector`` (batched env, the transform stack, actor,
   exploration) against a bare loop that steps the same ``JuggleEnv``s (same frame_skip, same
   number of envs) with the same actor network and expert-centred noise, resetting dropped envs.
   Target: ratio >= 0.5. The ratio is printed last. With ``teacher.policy=closed_loop`` the
   collector also runs that teacher for every env of the batch (the bare loop does not).

3. With ``--ray ADDRESS``: env steps/s of TorchRL's ``RayCollector`` on that cluster, with
   ``--collectors`` remote collectors of ``num_envs / collectors`` envs each (the same stack and
   policy, weights sent to them), against the in-process collector.

Trailing ``key=value`` arguments override ``configs/train.yaml`` (e.g. ``collector.num_envs=16``).
"""

from __future__ import annotations

import argparse
import copy
import statistics
import tempfile
import time
from pathlib import Path

import numpy as np
import torch
from hydra import compose, initialize_config_dir
from torchrl.collectors import Collector
from torchrl.envs.utils import ExplorationType, set_exploration_type

from jugglerl.batch.env_stack import make_env, normalisation
from jugglerl.cluster.ray_tasks import connect
from jugglerl.config.envs import make_juggle_env
from jugglerl.offpolicy.losses.ddpg import DDPG
from jugglerl.offpolicy.training import OffPolicyTraining


def median_time(run, repeats: int) -> float:
    timings = []
    for _ in range(repeats):
        start = time.perf_counter()
        run()
        timings.append(time.perf_counter() - start)
    return statistics.median(timings)


# --- updates ------------------------------------------------------------------------------------
class BareDDPG:
    """DDPG's update written directly in PyTorch on plain ``nn.Module``s."""

    def __init__(self, actor: torch.nn.Module, critic: torch.nn.Module, cfg):
        self.actor, self.critic = actor, critic
        self.actor_target, self.critic_target = copy.deepcopy(actor), copy.deepcopy(critic)
        self.actor_optimiser = torch.optim.Adam(actor.parameters(), lr=cfg.optim.lr_actor)
        self.critic_optimiser = torch.optim.Adam(critic.parameters(), lr=cfg.optim.lr_critic)
        self.gamma, self.tau, self.clip = cfg.algo.gamma, cfg.algo.tau, cfg.optim.max_grad_norm

    def __call__(self, obs, action, reward, next_obs, terminated) -> None:
        with torch.no_grad():
            next_q = self.critic_target(torch.cat([next_obs, self.actor_target(next_obs)], -1))
            target = reward + self.gamma * (1 - terminated) * next_q
        critic_loss = (self.critic(torch.cat([obs, action], -1)) - target).pow(2).mean()
        for p in self.critic.parameters():
            p.requires_grad_(False)
        actor_loss = -self.critic(torch.cat([obs, self.actor(obs)], -1)).mean()
        for p in self.critic.parameters():
            p.requires_grad_(True)
        self.actor_optimiser.zero_grad()
        self.critic_optimiser.zero_grad()
        (actor_loss + critic_loss).backward()
        torch.nn.utils.clip_grad_norm_(self.actor.parameters(), self.clip)
        torch.nn.utils.clip_grad_norm_(self.critic.parameters(), self.clip)
        self.actor_optimiser.step()
        self.critic_optimiser.step()
        with torch.no_grad():
            for net, target_net in (
                (self.actor, self.actor_target),
                (self.critic, self.critic_target),
            ):
                torch._foreach_lerp_(
                    list(target_net.parameters()), list(net.parameters()), self.tau
                )


def bare_actor(training: OffPolicyTraining) -> torch.nn.Module:
    """The MLP actor's network (MLP then tanh) as a plain module."""
    return copy.deepcopy(training.actor.module[0].module)


def bench_updates(
    training: OffPolicyTraining, cfg, updates: int, repeats: int
) -> tuple[float, float]:
    """Seconds per update (medians): ours, bare. Both on the same fixed batch."""
    with torch.no_grad():
        data = Collector(training.env, training.policy, frames_per_batch=2048, total_frames=2048)
        for batch in data:
            training.buffer.extend(batch)
        data.shutdown(close_env=False)
    batch = training.buffer.sample()
    critic = copy.deepcopy(training.update.loss.value_network.module)
    ours = DDPG(training.actor, batch["state"].shape[-1], training.env.action_spec, cfg)
    bare = BareDDPG(bare_actor(training), critic, cfg)
    tensors = (
        batch["state"],
        batch["action"],
        batch["next", "reward"],
        batch["next", "state"],
        batch["next", "terminated"].float(),
    )
    ours_times, bare_times = [], []
    for _ in range(repeats):  # alternate, so that drifts of the machine hit both alike
        ours_times.append(median_time(lambda: [ours(batch) for _ in range(updates)], 1))
        bare_times.append(median_time(lambda: [bare(*tensors) for _ in range(updates)], 1))
    return statistics.median(ours_times) / updates, statistics.median(bare_times) / updates


# --- collection ---------------------------------------------------------------------------------
def bench_collector(training: OffPolicyTraining, frames: int, repeats: int) -> float:
    """Env steps/s of TorchRL's Collector over the training env stack and exploration policy."""
    batch = training.cfg.collector.frames_per_batch

    def collect():
        collector = Collector(
            training.env, training.policy, frames_per_batch=batch, total_frames=frames
        )
        for _ in collector:
            pass
        collector.shutdown(close_env=False)

    with torch.no_grad(), set_exploration_type(ExplorationType.RANDOM):
        return frames / median_time(collect, repeats)


def bench_bare_loop(training: OffPolicyTraining, cfg, frames: int, repeats: int) -> float:
    """Env steps/s of plain JuggleEnvs stepped in a Python loop by the same actor network, with
    the same expert-centred Gaussian exploration (so the ball spends as long in the cup, where
    physics costs most, as in the collector)."""
    envs = [make_juggle_env(cfg.env) for _ in range(cfg.collector.num_envs)]
    actor = bare_actor(training)
    noise = training.noise
    times = torch.zeros(len(envs))
    observations = np.stack([env.reset(seed=i)[0] for i, env in enumerate(envs)])

    def loop():
        nonlocal observations
        for _ in range(frames // len(envs)):
            inputs = torch.as_tensor(observations, dtype=torch.float32)
            inputs = torch.cat([inputs, torch.zeros(len(envs), 3)], -1)  # the time features
            actions = actor(inputs)
            centre = noise.centre.reference(times).float()
            actions = actions + noise.expert_weight * (centre - actions)
            actions = (actions + noise.sigma * torch.randn_like(actions)).clamp(-1, 1).numpy()
            for i, env in enumerate(envs):
                observations[i], _, terminated, truncated, info = env.step(actions[i])
                if terminated or truncated:
                    observations[i], info = env.reset()
                times[i] = info["time"]

    with torch.no_grad():
        return frames / median_time(loop, repeats)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--frames", type=int, default=20000, help="env steps per collection timing")
    parser.add_argument("--updates", type=int, default=300, help="updates per update timing")
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--ray", metavar="ADDRESS", help="also time RayCollector on this cluster")
    parser.add_argument("--collectors", type=int, default=2, help="RayCollector's collectors")
    args, overrides = parser.parse_known_args()
    configs = Path(__file__).resolve().parents[2] / "configs"
    with initialize_config_dir(str(configs), version_base="1.3"):
        cfg = compose(
            "train", overrides=["algo=ddpg", "actor=mlp", "exploration=gaussian", *overrides]
        )
    torch.set_num_threads(1)  # the collector and the bare loop each run on one core
    with tempfile.TemporaryDirectory() as run_dir:  # the run writes nothing; it lends its parts
        training = OffPolicyTraining(cfg, run_dir)  # env stack, actor, exploration, update
        measure(training, cfg, args)
        training.close()


def measure(training: OffPolicyTraining, cfg, args: argparse.Namespace) -> None:
    """Print the update timings, the collection rates and, last, the collection ratio."""
    ours_update, bare_update = bench_updates(training, cfg, args.updates, args.repeats)
    print(
        f"DDPG update, batch {cfg.replay_buffer.batch_size}: ours {ours_update * 1e3:.2f} ms,"
        f" bare PyTorch {bare_update * 1e3:.2f} ms, ratio {ours_update / bare_update:.2f}"
        " (target <= 1.2)"
    )
    ours = bench_collector(training, args.frames, args.repeats)
    bare = bench_bare_loop(training, cfg, args.frames, args.repeats)
    teacher = "" if cfg.teacher.policy is None else f" with teacher {cfg.teacher.policy}"
    print(
        f"collection, {cfg.collector.num_envs} envs: bare loop {bare:,.0f} env steps/s,"
        f" TorchRL collector{teacher} {ours:,.0f} env steps/s"
    )
    if args.ray:
        remote = bench_ray_collector(training, cfg, args)
        print(
            f"RayCollector, {args.collectors} collectors x"
            f" {cfg.collector.num_envs // args.collectors} envs: {remote:,.0f} env steps/s,"
            f" ratio to the in-process collector {remote / ours:.2f}"
        )
    print(f"ratio {ours / bare:.2f} (target >= 0.5)")


def bench_ray_collector(training: OffPolicyTraining, cfg, args: argparse.Namespace) -> float:
    """Env steps/s of TorchRL's RayCollector, after one untimed batch (its actors start)."""
    from torchrl.collectors.distributed import RayCollector

    connect(args.ray)
    norm = normalisation(training.env)
    loc, scale = norm.loc.clone(), norm.scale.clone()
    envs = cfg.collector.num_envs // args.collectors
    batch = cfg.collector.frames_per_batch
    collector = RayCollector(
        [lambda: make_env(cfg, envs, loc, scale)] * args.collectors,
        training.policy,
        frames_per_batch=batch,
        total_frames=batch * (1 + args.frames // batch),
        remote_configs={"num_cpus": 1, "memory": 1024**3},
        sync=False,
    )
    batches = iter(collector)
    next(batches)
    start = time.perf_counter()
    frames = sum(data.numel() for data in batches)
    rate = frames / (time.perf_counter() - start)
    collector.shutdown()
    return rate


if __name__ == "__main__":
    main()
