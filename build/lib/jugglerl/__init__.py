"""JuggleRL: teach a simulated UR5e with a cone cup to juggle a ball.

Importing ``jugglerl`` registers the Gymnasium id ``JuggleRL/Juggle-v0``; it imports no torch.
"""

from jugglerl_envs import ENV_ID, JuggleEnv

__all__ = ["ENV_ID", "JuggleEnv"]
