"""One home per physical constant (issue 40, item 3): g is rocklab.physics.constants.G only."""

import ast
from pathlib import Path

import rocklab
from rocklab.physics import constants, wall
from rocklab.seismic.accelerograms import _text


def test_g_has_one_value_and_one_home():
    root = Path(rocklab.__file__).parent
    literals = []
    for path in root.rglob("*.py"):
        for node in ast.walk(ast.parse(path.read_text(), str(path))):
            if isinstance(node, ast.Constant) and isinstance(node.value, float) and 9.7 < node.value < 9.9:
                literals.append(f"{path.relative_to(root)}:{node.lineno}")
    assert literals == ["physics/constants.py:5"]
    assert wall.G is constants.G and _text.UNIT_FACTORS["g"] == constants.G == 9.80665
