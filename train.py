"""The project's main job. Training lands with the agents; until then, a demonstration throw."""

from dice_env.demo import main

if __name__ == "__main__":
    main()
