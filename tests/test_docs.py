"""The README's examples stay true: its system file is valid and its commands exist."""

import re
from pathlib import Path

import tomllib
from typer.testing import CliRunner

from satchain import ImagingSystem
from satchain.cli.main import app

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


TUTORIAL = Path(__file__).resolve().parents[1] / "docs" / "tutorial.md"


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


def test_readme_python_api_example_runs(monkeypatch, tmp_path, capsys, reduced_scene_toml):
    """The README's Python API block, on the reduced scene as its my_scene.toml: every check printed."""
    (block,) = re.findall(r"```python\n(.*?)```", README.read_text(), re.S)
    (tmp_path / "my_scene.toml").write_text(reduced_scene_toml)
    monkeypatch.chdir(tmp_path)
    namespace: dict = {"__name__": "readme"}
    exec(compile(block, "README.md[python]", "exec"), namespace)  # noqa: S102
    result = namespace["result"]
    assert result.passed is True and result.measurements.snr.snr > 0
    out = capsys.readouterr().out
    assert all(row.figure in out for row in result.comparison.rows)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["my_scene.toml"]  # nothing written without out_dir
