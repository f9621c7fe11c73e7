"""The documentation site builds with ``mkdocs build --strict`` (no warning: every page in the nav, every link and
cross-reference resolved), and its generated reference (docs/_hooks/reference.py) holds what the code defines:
every key of a system file and of a run configuration with its unit and range, every command and option of the CLI,
the public API, results.json's fields, the changelog.

The example notebook is converted here without being run (SATCHAIN_DOCS_EXECUTE=false); CI's own strict build
runs it, and so does ``pytest --nbmake docs/notebooks``."""

from __future__ import annotations

import html
import os
import re
import subprocess
import sys
import typing
from pathlib import Path

import pytest

for _plugin in ("mkdocs", "material", "mkdocstrings_handlers.python", "mkdocs_jupyter"):
    pytest.importorskip(_plugin, reason=f"the docs extras are not installed ({_plugin}): pip install -e '.[docs]'")

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def site(tmp_path_factory: pytest.TempPathFactory) -> Path:
    built = os.environ.get("SATCHAIN_DOCS_SITE")  # .ci/run builds the site (--strict) in a step of its own
    if built and (Path(built) / "index.html").is_file():
        return Path(built)
    out = tmp_path_factory.mktemp("site")
    env = {**os.environ, "SATCHAIN_DOCS_EXECUTE": "false", "NO_MKDOCS_2_WARNING": "1"}
    proc = subprocess.run(
        [sys.executable, "-m", "mkdocs", "build", "--strict", "-f", str(ROOT / "mkdocs.yml"), "-d", str(out)],
        cwd=ROOT,
        env=env,
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert proc.returncode == 0, f"mkdocs build --strict failed:\n{proc.stdout[-4000:]}\n{proc.stderr[-8000:]}"
    return out


def _text(site: Path, page: str) -> str:
    """A built page's article as plain text (tags dropped, entities decoded, whitespace collapsed)."""
    raw = (site / page / "index.html").read_text(encoding="utf-8")
    article = raw[raw.find("<article") : raw.find("</article>")]
    return " ".join(html.unescape(re.sub(r"<[^>]+>", " ", article)).split())


def _rows(site: Path, page: str) -> dict[str, list[str]]:
    """The table rows of a built page by their first cell (text only)."""
    raw = (site / page / "index.html").read_text(encoding="utf-8")
    rows = {}
    for tr in re.findall(r"<tr>(.*?)</tr>", raw, flags=re.S):
        cells = [
            " ".join(html.unescape(re.sub(r"<[^>]+>", " ", c)).split()) for c in re.findall(r"<td>(.*?)</td>", tr, re.S)
        ]
        if cells:
            rows.setdefault(cells[0], cells[1:])
    return rows


def _model_in(annotation: object) -> type | None:
    """The pydantic model a field holds (``Spiders | None``, ``tuple[Oscillation, ...]``), or None."""
    from pydantic import BaseModel

    if isinstance(annotation, type) and issubclass(annotation, BaseModel):
        return annotation
    for arg in typing.get_args(annotation):
        model = _model_in(arg)
        if model is not None:
            return model
    return None


def _keys(model: type, prefix: str = "", stop: tuple[str, ...] = ()) -> list[str]:
    """Every key of a model, nested tables as ``section.key``."""
    out = []
    for name, field in model.model_fields.items():  # type: ignore[attr-defined]
        key = f"{prefix}.{name}" if prefix else name
        out.append(key)
        sub = _model_in(field.annotation)
        if sub is not None and key not in stop:
            out += _keys(sub, key, stop)
    return out


def test_system_keys_every_field_with_unit_and_range(site: Path) -> None:
    from satchain.config.system import ImagingSystem

    rows = _rows(site, "reference/system-keys")
    # optics.f_number: Type | Unit | Range | Default | Description
    assert rows["optics.f_number"][0] == "number"
    assert rows["optics.f_number"][2] == "(0, 1000]"
    assert rows["optics.obscuration_ratio"][2:4] == ["[0, 1)", "0.0"]
    assert rows["orbit.altitude_m"][1] == "m"
    assert rows["orbit.altitude_m"][3] == "required"
    assert rows["motion.oscillation.frequency_hz"][1] == "Hz"
    keys = _keys(ImagingSystem)
    assert len(keys) > 60 and "optics.spiders.width_m" in keys
    missing = [k for k in keys if k not in rows]
    assert not missing, f"system keys missing from the reference: {missing}"
    assert "detector.pitch_m" in rows and "motion.line_of_sight.file" in rows  # the loader's extra keys


def test_run_keys(site: Path) -> None:
    from satchain.config.run import RunConfig

    rows = _rows(site, "reference/run-keys")
    keys = _keys(RunConfig, stop=("system.inline", "as_built"))
    assert "scene.pixel_m" in keys
    missing = [k for k in keys if k not in rows]
    assert not missing, f"run configuration keys missing from the reference: {missing}"
    assert rows["tolerances.edge_angle_deg"][1:4] == ["deg", "(0, inf)", "0.2"]


def test_cli_reference_lists_every_command_and_option(site: Path) -> None:
    import typer

    from satchain.cli import app

    text = _text(site, "reference/cli")
    root = typer.main.get_command(app)
    ctx = root.context_class(root, info_name="satchain")
    for name in root.list_commands(ctx):
        assert f"satchain {name}" in text
    measure = root.get_command(ctx, "measure")
    edge = measure.get_command(measure.context_class(measure, info_name="measure", parent=ctx), "edge")
    assert "satchain measure edge [OPTIONS]" in text
    for param in edge.params:
        for opt in param.opts:
            assert opt in text, opt
    raw = (site / "reference/cli/index.html").read_text(encoding="utf-8")
    section = raw[raw.find('id="satchain-measure-edge"') :]
    section = section[: section.find('id="satchain-measure-star"')]
    assert "--frequency-axis" in section and "normal" in section and "ISO 12233" in section


def test_api_reference(site: Path) -> None:
    import satchain

    text = _text(site, "reference/api")
    for name in satchain._LAZY:
        assert f"satchain.{name}" in text, name
    assert "EdgeResult" in text and "ConfigError" in text and "cy_per_mm_to_cy_per_px" in text
    raw = (site / "reference/api/index.html").read_text(encoding="utf-8")
    assert 'href="satchain.measure.edge/#satchain.measure.edge.measure_edge"' in raw
    edge = (site / "reference/api/satchain.measure.edge/index.html").read_text(encoding="utf-8")
    assert 'id="satchain.measure.edge.measure_edge"' in edge
    assert ":func:`" not in edge and ":class:`" not in edge  # the docstrings' reST roles became links or code
    assert not (site / "reference/api/satchain._moved").exists()


def test_results_json_and_changelog(site: Path) -> None:
    rows = _rows(site, "reference/results-json")
    assert "format_version" in rows and "summary" in rows
    assert "slanted_edges[].mtf_at_nyquist_measured" in rows
    changelog = _text(site, "changelog")
    assert "Keep a Changelog" in changelog and "Unreleased" in changelog
