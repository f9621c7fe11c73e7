"""The documentation's examples stay true: the README's first lines and tour, the system file of
docs/guide/budget.md, the Python API block of docs/guide/python-api.md and the tutorial."""

import re
from pathlib import Path

import tomllib
from typer.testing import CliRunner

from satchain import ImagingSystem
from satchain.cli.main import app

ROOT = Path(__file__).resolve().parents[1]
README = ROOT / "README.md"
BUDGET = ROOT / "docs" / "guide" / "budget.md"
PYTHON_API = ROOT / "docs" / "guide" / "python-api.md"


def system_file_example() -> str:
    """The system file of docs/guide/budget.md ("A system file"), written there by ``cat > mycamera.toml``."""
    section = BUDGET.read_text().split("### A system file", 1)[1]
    return re.search(r"^cat > mycamera\.toml <<'EOF'\n(.*?)^EOF$", section, re.S | re.M).group(1)


def test_system_file_example_is_valid():
    toml = system_file_example()
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


TUTORIAL = ROOT / "docs" / "tutorial.md"


def test_tutorial_runs_end_to_end(monkeypatch, tmp_path, capsys):
    """Every python block of docs/tutorial.md, in order, in one namespace (as a notebook would)."""
    blocks = re.findall(r"```python\n(.*?)```", TUTORIAL.read_text(), re.S)
    assert len(blocks) >= 6
    monkeypatch.chdir(tmp_path)
    namespace: dict = {"__name__": "tutorial"}
    for i, code in enumerate(blocks):
        exec(compile(code, f"{TUTORIAL.name}[block {i}]", "exec"), namespace)  # noqa: S102
    assert namespace["result"].passed is not False
    assert not list(tmp_path.iterdir())  # satchain.run without out_dir writes nothing
    assert "MTF@Nyquist" in capsys.readouterr().out


def test_python_api_example_runs(monkeypatch, tmp_path, capsys, reduced_scene_toml):
    """The Python API page's block, on its my_scene.toml (the reduced scene): every check printed."""
    text = PYTHON_API.read_text()
    (block,) = re.findall(r"```python\n(.*?)```", text, re.S)
    scene = re.search(r"^cat > my_scene\.toml <<'EOF2'\n(.*?)^EOF2$", text, re.S | re.M).group(1)
    assert tomllib.loads(scene) == tomllib.loads(reduced_scene_toml)
    (tmp_path / "my_scene.toml").write_text(scene)
    monkeypatch.chdir(tmp_path)
    namespace: dict = {"__name__": "readme"}
    exec(compile(block, "python-api.md[python]", "exec"), namespace)  # noqa: S102
    result = namespace["result"]
    assert result.passed is True and result.measurements.snr.snr > 0
    out = capsys.readouterr().out
    assert all(row.figure in out for row in result.comparison.rows)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["my_scene.toml"]  # nothing written without out_dir
