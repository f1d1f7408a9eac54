"""The README is a page a person acts on: its library example runs and does what it says, and
its two start-here commands are the ones CI runs."""

import re
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[1]
README = (ROOT / "README.md").read_text()


def python_blocks() -> list[str]:
    return re.findall(r"```python\n(.*?)```", README, flags=re.S)


def test_the_library_example_drops_the_square_onto_the_sphere_and_not_through_it(capsys):
    """The example's half second: the square has fallen onto the sphere (its nearest node within
    a thickness and a millimetre of the surface) and no node is inside it."""
    (block,) = python_blocks()
    namespace: dict = {}
    exec(compile(block, "README.md", "exec"), namespace)
    radius = namespace["radius"]
    thickness = namespace["fabric_by_name"]("cotton").thickness
    assert radius.min() >= 0.3
    assert radius.min() <= 0.3 + thickness + 1e-3
    assert np.isfinite(namespace["state"].positions()).all()
    assert re.fullmatch(r"nearest node \d+\.\d mm from the centre of a 300 mm sphere\n", capsys.readouterr().out)


def test_the_start_here_test_command_is_the_one_ci_runs():
    commands = re.findall(r"^    (python3 -m pip install .*)$", README, flags=re.M)
    assert commands[0] == "python3 -m pip install -e . && party run dress --out out/dress"
    assert commands[1] in (ROOT / ".ci" / "run").read_text().splitlines()
