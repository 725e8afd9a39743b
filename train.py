"""The main job: train PPO on a named task (--env-id; DiceThrow-v0 by default), evaluate, report.

A thin entry into :mod:`agents.train`; ``python train.py --help`` lists every option.
"""

from agents.train import main

if __name__ == "__main__":
    main()
