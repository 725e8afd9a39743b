import subprocess
from importlib import metadata

from dice_env.provenance import CHECKOUT, code_version


def test_a_checkout_gives_its_git_describe():
    described = subprocess.run(["git", "describe", "--always", "--dirty"], cwd=CHECKOUT,
                               capture_output=True, text=True, check=True).stdout.strip()
    assert code_version() == described == code_version(str(CHECKOUT))


def test_outside_a_checkout_the_installed_version_or_unknown(tmp_path):
    try:
        expected = f"dice_env {metadata.version('dice_env')}"
    except metadata.PackageNotFoundError:
        expected = "unknown"
    assert code_version(tmp_path) == expected
