"""The project's main job: train PPO on DiceThrow-v0, evaluate it and write its report.

A thin entry into :mod:`agents.train`; ``python train.py --help`` lists every option.
"""

from agents.train import main

if __name__ == "__main__":
    main()
