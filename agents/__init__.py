"""Agents for DiceThrow-v0: PPO training, baselines, a search oracle and the evaluation report."""
