"""dice_env: a thrown die as a compiled batched simulator (Sinha & Yu's corner-node model)."""

from dice_env import envs  # registers the Gymnasium env DiceThrow-v0
from dice_env.model.die import Die
from dice_env.model.scene import ContactLaw, FrictionLaw, Ground, Rest, Scene, Scheme, Wall
from dice_env.simulation.simulate import Result, State, simulate

__all__ = ["ContactLaw", "Die", "FrictionLaw", "Ground", "Rest", "Result", "Scene", "Scheme",
           "State", "Wall", "envs", "simulate"]
