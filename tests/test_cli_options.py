"""The options the ``satchain measure`` commands share are defined once (``satchain.cli.options``, as
rasterio's ``rio/options.py``): every command uses the same option object, an option name has one meaning
(flags, help text, type) across the commands, and a bad value gets the same one-line error from each."""

from __future__ import annotations

import inspect
import json
import typing

import numpy as np
import pytest
import typer
from typer.testing import CliRunner

from satchain.cli.main import app
from satchain.cli.measure import COMMANDS, measure_app
from satchain.cli.options import SHARED_OPTIONS, ImageArg

#: Options that are (rightly) each command's own although two commands have them: ``--direction`` is what the
#: bars run along (bars: default ACT) or the wedge's resolution direction (wedge: default ALT).
OWN_MEANING = {"--direction"}


def _click_commands() -> dict:
    return typer.main.get_command(measure_app).commands


def _long_name(param) -> str:
    return next(o for o in param.opts if o.startswith("--"))


def _type(param) -> str:
    """The value type of a click/typer option (typer >= 0.2x keeps it in ``type_descriptor``)."""
    descriptor = getattr(param, "type_descriptor", None)
    return str(descriptor.annotation) if descriptor is not None else param.type.name


def _infos(fn) -> dict:
    """``{parameter: typer Option/ArgumentInfo}`` read from the command function's ``Annotated`` hints."""
    hints = typing.get_type_hints(inspect.unwrap(fn), include_extras=True)
    out = {}
    for name, hint in hints.items():
        infos = [m for m in getattr(hint, "__metadata__", ()) if isinstance(m, typer.models.ParameterInfo)]
        if infos:
            out[name] = infos[0]
    return out


def test_every_command_is_registered_once_on_the_measure_app():
    assert list(_click_commands()) == list(COMMANDS) == ["edge", "star", "bars", "wedge", "auto", "find", "jitter",
                                                            "registration"]
    assert [c.callback.__wrapped__ for c in measure_app.registered_commands] == [
        inspect.unwrap(f) for f in COMMANDS.values()
    ]


def test_a_shared_option_is_the_same_object_in_every_command():
    shared_infos = {name: [t.__metadata__[0] for t in types] for name, types in SHARED_OPTIONS.items()}
    users = {name: [] for name in SHARED_OPTIONS}
    for cmd, fn in COMMANDS.items():
        infos = _infos(fn)
        assert infos["image"] is ImageArg.__metadata__[0], cmd
        for info in infos.values():
            decls = [info.default, *(info.param_decls or ())]  # Annotated: typer keeps the first flag in .default
            long = next((d for d in decls if isinstance(d, str) and d.startswith("--")), None)
            if long in shared_infos:
                assert any(info is s for s in shared_infos[long]), f"{cmd}: {long} is redefined locally"
                users[long].append(cmd)
    assert users["--roi"] == ["edge", "star", "bars", "wedge", "jitter", "registration"]
    assert users["--pixel-m"] == users["--json"] == users["--out"] == list(COMMANDS)
    assert users["--truth"] == users["--origin-m"] == users["--threshold"] == ["wedge", "auto"]


def test_an_option_name_means_one_thing_across_the_commands():
    seen: dict[str, dict] = {}
    for cmd, command in _click_commands().items():
        for p in command.params:
            if p.param_type_name != "option":
                continue
            long = _long_name(p)
            seen.setdefault(long, {})[cmd] = (tuple(sorted(p.opts)), p.help, _type(p), p.is_flag, p.multiple)
    repeated = {name: per_cmd for name, per_cmd in seen.items() if len(per_cmd) > 1 and name != "--help"}
    assert {"--roi", "--pixel-m", "--json", "--out", "--truth", "--origin-m", "--threshold"} <= set(repeated)
    for name, per_cmd in repeated.items():
        if name in OWN_MEANING:
            continue
        assert name in SHARED_OPTIONS, f"{name} is defined in {sorted(per_cmd)}: define it once in cli_options"
        assert len(set(per_cmd.values())) == 1, (name, per_cmd)
    # the defaults agree too (only --truth differs: required for auto, optional for wedge)
    defaults = {
        (cmd, _long_name(p)): p.default
        for cmd, c in _click_commands().items()
        for p in c.params
        if p.param_type_name == "option"
    }
    assert defaults["wedge", "--threshold"] == defaults["auto", "--threshold"] == 0.15
    assert {defaults[c, "--pixel-m"] for c in COMMANDS} == {None}


# ------------------------------------------------------------------------------- the same parsing, the same error


@pytest.fixture(scope="module")
def inputs(tmp_path_factory):
    d = tmp_path_factory.mktemp("opts")
    np.save(d / "img.npy", np.random.default_rng(1).random((80, 80)))
    (d / "truth.json").write_text(json.dumps({"items": []}))
    return {"img": str(d / "img.npy"), "truth": str(d / "truth.json")}


# what each command needs besides IMAGE to reach the parsing of a shared option
REQUIRED = {
    "edge": [],
    "star": ["--cycles", "16"],
    "bars": ["--periods-px", "4"],
    "wedge": ["--line-width-start-px", "1", "--line-width-end-px", "4"],
    "auto": ["--truth", "{truth}"],
    "find": [],
    "jitter": ["--line-time", "1e-3"],
    "registration": ["--band", "1"],
}


def _error(args: list[str], inputs) -> str:
    r = CliRunner().invoke(app, ["measure", *(a.format(**inputs) for a in args)])
    assert r.exit_code == 2, (args, r.output)
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: "), (args, r.stderr)
    return lines[0]


@pytest.mark.parametrize(
    ("option", "value", "expected"),
    [
        ("--pixel-m", "-1", "--pixel-m"),
        ("--roi", "1,2,3", "--roi = '1,2,3': must be 4 comma-separated numbers"),
        ("--roi", "0,0,40.5,40", "--roi = '0,0,40.5,40': must be four integers X0,Y0,X1,Y1 (pixels)"),
    ],
)
def test_a_bad_shared_value_gets_the_same_error_from_every_command(inputs, option, value, expected):
    users = [cmd for cmd, c in _click_commands().items() if any(option in p.opts for p in c.params)]
    assert len(users) >= 4
    errors = {cmd: _error([cmd, "{img}", *REQUIRED[cmd], option, value], inputs) for cmd in users}
    assert len(set(errors.values())) == 1, errors
    assert next(iter(errors.values())).startswith(f"error: {expected}")


def test_a_bad_origin_gets_the_same_error_from_wedge_and_auto(inputs):
    wedge = _error(["wedge", "{img}", "--truth", "{truth}", "--origin-m", "5"], inputs)
    auto = _error(["auto", "{img}", "--truth", "{truth}", "--origin-m", "5"], inputs)
    assert wedge == auto == "error: --origin-m = '5': must be 2 comma-separated numbers"


def test_the_old_module_still_offers_its_names():
    # code written before the split (issue 18) imports these from satchain.cli.measure
    import satchain.cli.measure as old
    from satchain.cli import options as cli_options
    from satchain.cli import output as cli_output

    assert old.ImageArg is cli_options.ImageArg and old.RoiOpt is cli_options.RoiOpt
    assert old.PixelOpt is cli_options.PixelOpt and old.JsonOpt is cli_options.JsonOpt
    assert old.OutOpt is cli_options.OutOpt and old._load is cli_options.load_image
    assert old._roi is cli_options.parse_roi and old._emit is cli_output.emit and old._fmt is cli_output.fmt
