"""The README's examples stay true: its system file is valid and its commands exist."""

import re
from pathlib import Path

import tomllib
from typer.testing import CliRunner

from satchain import ImagingSystem
from satchain.cli import app

README = Path(__file__).resolve().parents[1] / "README.md"


def test_readme_system_file_is_valid():
    toml = re.search(r"```toml\n(.*?)```", README.read_text(), re.S).group(1)
    s = ImagingSystem.from_dict(tomllib.loads(toml))
    assert s.gsd_alt_m == 567e3 * 5.88e-6 / (0.70 * 9.72)
    assert s.optics.needs_pupil_fft  # spiders and Zernike terms ask for the pupil FFT
    assert s.atmosphere.turbulence


def test_readme_first_lines_are_the_two_commands():
    lines = README.read_text().splitlines()
    block = lines[lines.index("```bash") + 1 : lines.index("```bash") + 3]
    assert block == [
        "python -m pip install -e . && satchain run",
        "python -m pip install -e '.[test]' && python -m pytest -q -n 2",
    ]


def test_every_command_in_the_tour_exists():
    text = README.read_text()
    blocks = "\n".join(re.findall(r"```bash\n(.*?)```", text, re.S))
    commands = set(re.findall(r"^satchain (\w+)", blocks, re.M))
    assert {"run", "budget", "scene", "simulate", "measure"} <= commands
    for cmd in sorted(commands):
        assert CliRunner().invoke(app, [cmd, "--help"]).exit_code == 0, cmd
