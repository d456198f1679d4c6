"""``ou``: TorchRL's Ornstein-Uhlenbeck noise added to the actor's action (the paper's first try).

``exploration.theta``, ``mu``, ``sigma`` shape the process; ``eps_init`` → ``eps_end`` scales it
over ``annealing_frames``.
"""

from torchrl.modules import OrnsteinUhlenbeckProcessModule

from jugglerl.offpolicy.exploration import EXPLORATIONS


@EXPLORATIONS.register("ou")
def ou_noise(exploration_cfg, action_spec) -> OrnsteinUhlenbeckProcessModule:
    return OrnsteinUhlenbeckProcessModule(
        spec=action_spec,
        eps_init=exploration_cfg.eps_init,
        eps_end=exploration_cfg.eps_end,
        annealing_num_steps=exploration_cfg.annealing_frames,
        theta=exploration_cfg.theta,
        mu=exploration_cfg.mu,
        sigma=exploration_cfg.sigma,
    )
