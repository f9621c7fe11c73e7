"""mkdocs hooks (``hooks:`` in mkdocs.yml) that generate the reference pages at build time, from the code:

* ``reference/api/index.md``: the public API (``satchain._LAZY``, the result types, ``satchain.errors``,
  ``satchain.units``), each name linked to its entry in the module pages;
* ``reference/api/<module>.md``: one mkdocstrings page per public package and module (``_private`` ones skipped),
  listed in the nav under "API modules" (the nav entry ``reference/api/modules.md`` is expanded here);
* ``reference/cli.md``: every command and subcommand of the typer app, from its click objects;
* ``reference/system-keys.md``, ``reference/run-keys.md``, ``reference/study-keys.md``: every key of a system
  file, of a run configuration and of a study file, from the pydantic models' JSON Schemas
  (:mod:`satchain.config.schema`, as ``satchain schema system|run|study``);
* ``reference/results-json.md``: the fields of results.json (``satchain schema results``).

Nothing here is committed as markdown: the pages exist only in the built site.
"""

from __future__ import annotations

import ast
import importlib
import inspect
import json
import re
from pathlib import Path
from typing import Any

from mkdocs.config.defaults import MkDocsConfig
from mkdocs.structure.files import File, Files

PACKAGE = "satchain"
API_DIR = "reference/api"
MODULES_PLACEHOLDER = f"{API_DIR}/modules.md"

_ROLE = re.compile(r":(?:py:)?[a-z]+:`~?\.?([^`]+)`")


# ------------------------------------------------------------------------------------------------- helpers
def _package_dir() -> Path:
    spec = importlib.util.find_spec(PACKAGE)  # type: ignore[attr-defined]
    assert spec is not None and spec.submodule_search_locations
    return Path(next(iter(spec.submodule_search_locations)))


def public_modules() -> list[str]:
    """Every public package and module of satchain, dotted, sorted (a ``_private`` part anywhere: skipped)."""
    root = _package_dir()
    names = []
    for path in sorted(root.rglob("*.py")):
        rel = path.relative_to(root.parent).with_suffix("")
        parts = list(rel.parts)
        if parts[-1] == "__init__":
            parts = parts[:-1]
        if any(p.startswith("_") for p in parts) or not (path.parent / "__init__.py").exists():
            continue
        names.append(".".join(parts))
    return sorted(set(names), key=lambda n: (n.split(".")[:-1] != [PACKAGE] and n != PACKAGE, n))


_CODE_SPAN = re.compile(r"(``.+?``|`[^`]+`)")


def _md_text(text: str, *, cell: bool = False) -> str:
    """Prose for markdown: outside code spans, a ``<`` that would open an HTML tag, a ``*`` and (in a table
    cell) a ``|`` are escaped; reST roles become code."""
    text = _ROLE.sub(lambda m: f"`{m.group(1)}`", text)
    parts = _CODE_SPAN.split(text)
    for i in range(0, len(parts), 2):  # the even parts are outside code spans
        part = re.sub(r"<(?=[A-Za-z/!?])", "&lt;", parts[i]).replace("*", "\\*")
        parts[i] = part.replace("|", "\\|") if cell else part
    return "".join(parts)


def _cell(text: Any) -> str:
    """A markdown table cell: one line, escaped (`_md_text`)."""
    return _md_text(" ".join(str(text).split()), cell=True)


def _summary(obj: Any) -> str:
    doc = inspect.getdoc(obj) or ""
    return _cell(doc.split("\n\n", 1)[0])


def _code(text: Any) -> str:
    s = str(text).replace("|", "\\|")
    return f"`{s}`" if "`" not in s else f"``{s}``"


# ------------------------------------------------------------------------------------------------- API
def _canonical(name: str, module: str, modules: set[str]) -> tuple[Any, str]:
    obj = getattr(importlib.import_module(module), name)
    home = getattr(obj, "__module__", None)
    qual = getattr(obj, "__qualname__", name)
    if isinstance(home, str) and home in modules and hasattr(importlib.import_module(home), qual.split(".")[0]):
        return obj, f"{home}.{qual}"
    return obj, f"{module}.{name}"


def _module_tree(mod: str) -> ast.Module:
    """A module's syntax tree, read without importing it."""
    path = _package_dir().parent / Path(*mod.split("."))
    path = path / "__init__.py" if path.is_dir() else path.with_suffix(".py")
    return ast.parse(path.read_text(encoding="utf-8"))


def _module_summary(mod: str) -> str:
    return _cell((ast.get_docstring(_module_tree(mod)) or "").split("\n\n", 1)[0])


def _result_types(modules: list[str]) -> list[tuple[str, str]]:
    """(module, class) of every top-level class named ``*Result`` in the public modules (read with ast)."""
    found = []
    for mod in modules:
        tree = _module_tree(mod)
        found += [(mod, n.name) for n in tree.body if isinstance(n, ast.ClassDef) and n.name.endswith("Result")]
    return found


def api_index(modules: list[str]) -> str:
    import satchain

    known = set(modules)
    out = [
        "# Public API",
        "",
        "What `import satchain` offers (its names are imported lazily, on first use). Each name links to its "
        "entry in the [module pages](#modules); the [command line](../cli.md) and the "
        "[configuration keys](../system-keys.md) have their own references. This page is generated from "
        "`satchain._LAZY`, `satchain.errors` and `satchain.units` when the site is built.",
        "",
        "```python",
        "import satchain",
        "",
        'system = satchain.load_preset("ankarasat3")',
        "```",
        "",
        "## Functions and classes",
        "",
        "| Name | Kind | Summary |",
        "| --- | --- | --- |",
    ]
    for name, module in satchain._LAZY.items():
        obj, path = _canonical(name, module, known)
        kind = "class" if inspect.isclass(obj) else "function" if callable(obj) else "data"
        out.append(f"| [`satchain.{name}`][{path}] | {kind} | {_summary(obj)} |")
    out += ["", "## Result types", "", "The records that the measurements, the budget and a run hand back.", ""]
    out += ["| Class | Summary |", "| --- | --- |"]
    for mod, cls_name in _result_types(modules):
        tree = _module_tree(mod)
        node = next(n for n in tree.body if isinstance(n, ast.ClassDef) and n.name == cls_name)
        summary = _cell((ast.get_docstring(node) or "").split("\n\n", 1)[0])
        out.append(f"| [`{cls_name}`][{mod}.{cls_name}] (`{mod}`) | {summary} |")
    for title, mod in (("Errors and warnings", "satchain.errors"), ("Units", "satchain.units")):
        tree = _module_tree(mod)
        out += ["", f"## {title}", "", f"[`{mod}`]({mod}.md): {_module_summary(mod)}", ""]
        out += ["| Name | Summary |", "| --- | --- |"]
        for node in tree.body:
            if isinstance(node, (ast.ClassDef, ast.FunctionDef)) and not node.name.startswith("_"):
                summary = _cell((ast.get_docstring(node) or "").split("\n\n", 1)[0])
                out.append(f"| [`{node.name}`][{mod}.{node.name}] | {summary} |")
    out += ["", "## Modules", "", "One page per public package and module:", ""]
    out += [f"- [`{mod}`]({mod}.md): {_module_summary(mod)}" for mod in modules]
    return "\n".join(out) + "\n"


def module_page(mod: str) -> str:
    return f"::: {mod}\n"


def _modules_nav(modules: list[str]) -> list[Any]:
    groups: dict[str, list[Any]] = {}
    for mod in modules:
        parts = mod.split(".")
        top = PACKAGE if len(parts) <= 2 and not (_package_dir() / parts[-1]).is_dir() else ".".join(parts[:2])
        groups.setdefault(top, []).append({mod: f"{API_DIR}/{mod}.md"})
    return [{top: items} for top, items in groups.items()]


# ------------------------------------------------------------------------------------------------- CLI
def _default_text(param: Any) -> str:
    default = getattr(param, "default", None)
    if getattr(param, "is_flag", False) and not getattr(param, "secondary_opts", None):
        return "false" if not default else "true"
    if default is None or callable(default) or repr(default).endswith("UNSET"):
        return ""
    if isinstance(default, bool):
        return str(default).lower()
    if isinstance(default, (list, tuple)):
        return ", ".join(map(str, default)) if default else ""
    return _code(getattr(default, "value", default))


def _param_row(param: Any, ctx: Any) -> str:
    record = param.get_help_record(ctx) if hasattr(param, "get_help_record") else None
    is_option = param.param_type_name == "option"
    names = [*param.opts, *param.secondary_opts] if is_option else [param.name]
    tokens = (record[0] if record else param.name).split()
    shown = tokens[0] if not is_option else ""
    # the metavar of the help record ("-o, --out <path>" -> "<path>"): the type as the help shows it
    rest = tokens[1:] if not is_option else [t for t in tokens if t.rstrip(",") not in (*names, "/")]
    metavar = " ".join(rest)
    if metavar.startswith("<") and metavar.endswith(">"):
        metavar = metavar[1:-1]
    repeatable = getattr(param, "multiple", False) or getattr(param, "nargs", 1) == -1
    listed = re.fullmatch(r"list\[(.+)\]", metavar)
    if listed:
        metavar, repeatable = listed.group(1), True
    if getattr(param, "is_flag", False):
        type_text = "flag"
    else:
        type_text = (metavar or "text") + (" (repeatable)" if repeatable else "")
    help_text = getattr(param, "help", None) or ""
    req = "yes" if param.required else ""
    name_cell = " / ".join(_code(n) for n in names) if is_option else _code(shown)
    return f"| {name_cell} | {_cell(type_text)} | {req} | {_default_text(param)} | {_cell(help_text)} |"


def _help_markdown(text: str) -> str:
    """A command's help as markdown paragraphs (HTML escaped; typer's ``\\b`` no-rewrap markers dropped)."""
    text = inspect.cleandoc(text or "").replace("\b\n", "").replace("\b", "")
    return _md_text(text)


def cli_page() -> str:
    import typer

    from satchain.cli import app

    root = typer.main.get_command(app)
    ctx_class = root.context_class
    out = [
        "# Command line",
        "",
        "Every command of `satchain`, with its options, generated from the typer app (`satchain.cli:app`) when "
        "the site is built. `satchain COMMAND --help` prints the same at the terminal.",
        "",
    ]

    def walk(cmd: Any, ctx: Any, path: str, depth: int) -> None:
        nonlocal out
        level = "#" * min(depth + 2, 6)
        out.append(f"{level} `{path}` {{ #{path.replace(' ', '-')} }}")
        out.append("")
        usage = " ".join(cmd.collect_usage_pieces(ctx))
        out += ["```text", f"{path} {usage}".rstrip(), "```", ""]
        if cmd.help:
            out += [_help_markdown(cmd.help), ""]
        params = [p for p in cmd.params if not getattr(p, "hidden", False)]
        if params:
            out += ["| Argument / option | Type | Required | Default | Help |", "| --- | --- | --- | --- | --- |"]
            out += [_param_row(p, ctx) for p in params]
            out += ["| `--help` | flag |  |  | show the help and exit |", ""]
        subcommands = cmd.list_commands(ctx) if hasattr(cmd, "list_commands") else []
        if subcommands:
            out += ["| Command | Summary |", "| --- | --- |"]
            for name in subcommands:
                sub = cmd.get_command(ctx, name)
                anchor = f"{path} {name}".replace(" ", "-")
                out.append(f"| [`{path} {name}`](#{anchor}) | {_cell(sub.get_short_help_str(200))} |")
            out.append("")
            for name in subcommands:
                sub = cmd.get_command(ctx, name)
                if getattr(sub, "hidden", False):
                    continue
                walk(sub, ctx_class(sub, info_name=name, parent=ctx), f"{path} {name}", depth + 1)

    walk(root, ctx_class(root, info_name=PACKAGE), PACKAGE, 0)
    return "\n".join(out) + "\n"


# ------------------------------------------------------------------------------------------------- keys
#: a $ref not expanded here: linked to its own page
_STOP = {"ImagingSystem": "system-keys.md", "RunConfig": "run-keys.md"}


def _ref_name(prop: dict[str, Any]) -> str | None:
    ref = prop.get("$ref")
    return ref.rsplit("/", 1)[-1] if isinstance(ref, str) else None


def _type_text(prop: dict[str, Any], defs: dict[str, Any]) -> str:
    if "const" in prop:
        return f"`{json.dumps(prop['const'])}`"
    if "enum" in prop:
        return " \\| ".join(f"`{json.dumps(v)}`" for v in prop["enum"])
    ref = _ref_name(prop)
    if ref is not None:
        return "table"
    if "anyOf" in prop:
        parts = []
        for alt in prop["anyOf"]:
            t = _type_text(alt, defs)
            if t not in parts:
                parts.append(t)
        return " \\| ".join(parts)
    t = prop.get("type")
    if isinstance(t, list):
        return " \\| ".join(t)
    if t == "array":
        items = prop.get("items", {})
        if _ref_name(items) is not None:
            return "array of tables"
        inner = _type_text(items, defs) if items else ""
        return f"array of {inner}" if inner else "array"
    if t == "object":
        extra = prop.get("additionalProperties")
        if isinstance(extra, dict) and extra:
            return f"table of {_type_text(extra, defs)}"
        return "table"
    return str(t) if t else "any"


def _bounds(prop: dict[str, Any]) -> str:
    """The allowed range ``[0, 1)`` of a property (its own bounds, an anyOf alternative's, its items')."""
    for cand in (prop, *prop.get("anyOf", ()), prop.get("items", {}), prop.get("additionalProperties") or {}):
        if not isinstance(cand, dict):
            continue
        lo = cand.get("exclusiveMinimum", cand.get("minimum"))
        hi = cand.get("exclusiveMaximum", cand.get("maximum"))
        if lo is None and hi is None:
            continue
        left = "(" if lo is None or "exclusiveMinimum" in cand else "["
        right = ")" if hi is None or "exclusiveMaximum" in cand else "]"
        return f"{left}{'-inf' if lo is None else f'{lo:g}'}, {'inf' if hi is None else f'{hi:g}'}{right}"
    return ""


def _sizes(prop: dict[str, Any]) -> str:
    for cand in (prop, *prop.get("anyOf", ())):
        lo, hi = cand.get("minItems"), cand.get("maxItems")
        if lo is not None or hi is not None:
            if lo == hi:
                return f"{lo} items"
            return f"{lo or 0} to {hi} items" if hi is not None else f"at least {lo} item{'s' * (lo != 1)}"
    return ""


def _description(prop: dict[str, Any]) -> str:
    """The key's own description, without the ``unit: ...`` and ``range ...`` that the schema appends (they have
    their columns)."""
    parts = [p for p in str(prop.get("description", "")).split("; ") if not p.startswith(("unit: ", "range "))]
    return "; ".join(parts)


def _unit(prop: dict[str, Any]) -> str:
    for cand in (prop, *prop.get("anyOf", ()), prop.get("items", {})):
        if isinstance(cand, dict) and cand.get("x-unit"):
            return str(cand["x-unit"])
    return ""


def _sub_ref(prop: dict[str, Any]) -> tuple[str | None, bool, dict[str, Any] | None]:
    """(the $defs model a key holds, whether as an array of tables, an inline table schema) or Nones."""
    for cand in (prop, *prop.get("anyOf", ())):
        if _ref_name(cand):
            return _ref_name(cand), False, None
        items = cand.get("items", {})
        if isinstance(items, dict) and _ref_name(items):
            return _ref_name(items), True, None
        if cand.get("type") == "object" and cand.get("properties"):
            return None, False, cand
    return None, False, None


def _anchor(section: str) -> str:
    return "keys-" + re.sub(r"[^a-z0-9]+", "-", section.lower()).strip("-") if section else "keys-top"


def keys_page(kind: str, title: str, intro: str, *, toml: bool = True) -> str:
    """A page with one table per section (a TOML table, or a JSON object when ``toml`` is false), each nested
    table right after its parent."""
    from satchain.config.schema import schema
    from satchain.config.schema import unit_of_key as unit_of_name
    from satchain.results import results_schema

    top = results_schema() if kind == "results" else schema(kind)
    defs = top.get("$defs", {})
    out: list[str] = []
    counts = {"keys": 0, "tables": 0}

    def section_table(section: str, model: dict[str, Any], is_array: bool) -> None:
        counts["tables"] += 1
        if not toml:
            header = "Top-level keys" if not section else f"`{section}[]`" if is_array else f"`{section}`"
        else:
            header = "Top-level keys" if not section else (f"[[{section}]]" if is_array else f"[{section}]")
        out.extend([f"## {header} {{ #{_anchor(section)} }}", ""])
        desc = str(model.get("description", "")).split("\n\n", 1)[0] if section else ""
        if desc:
            out.extend([_cell(desc), ""])
        alternatives = [alt.get("required", []) for alt in model.get("anyOf", []) if "required" in alt]
        in_alternative = {k for alt in alternatives for k in alt}
        if alternatives:
            either = ", or ".join(" and ".join(f"`{k}`" for k in alt) for alt in alternatives)
            out.extend([f"Required: {either}.", ""])
        out.extend(["| Key | Type | Unit | Range | Default | Description |", "| --- | --- | --- | --- | --- | --- |"])
        required = set(model.get("required", []))
        children: list[tuple[str, dict[str, Any], bool]] = []
        for name, prop in model.get("properties", {}).items():
            prefix = f"{section}[]" if is_array and not toml else section
            key = f"{prefix}.{name}" if section else name
            ref, as_array, inline = _sub_ref(prop)
            type_text = _type_text(prop, defs)
            if ref in _STOP:
                type_text = f"[{type_text}]({_STOP[ref]})"
            elif ref is not None and ref.startswith("AsBuilt"):
                type_text = f"[table](system-keys.md#{_anchor(name)}) (any of its keys)"
            elif ref is not None and ref in defs:
                children.append((key, defs[ref], as_array))
                type_text = f"[{type_text}](#{_anchor(key)})"
            elif inline is not None:
                children.append((key, inline, False))
                type_text = f"[table](#{_anchor(key)})"
            if "default" in prop:
                default = json.dumps(prop["default"])
            elif name in required:
                default = "required"
            elif name in in_alternative:
                default = "required (see above)"
            else:
                default = ""
            own = _description(prop)
            if not own and ref is not None and ref in defs:  # a table: its model's first sentence
                own = str(defs[ref].get("description", "")).split("\n\n", 1)[0]
            description = "; ".join(d for d in (own, _sizes(prop)) if d)
            unit = _unit(prop) or unit_of_name(name) or ""
            out.append(
                f"| `{key}` | {type_text} | {_cell(unit)} | {_cell(_bounds(prop))} | {_cell(default)} | "
                f"{_cell(description)} |"
            )
            counts["keys"] += 1
        out.append("")
        for child in children:
            section_table(*child)

    section_table("", top, False)
    head = [f"# {title}", "", intro, "", f"> {_cell(top.get('description', ''))}", ""]
    head += [f"{counts['keys']} keys in {counts['tables']} tables.", ""]
    return "\n".join(head + out) + "\n"


def results_page() -> str:
    return keys_page(
        "results",
        "results.json",
        "The fields of the `results.json` that `satchain run` writes, generated from the JSON Schema that "
        "`satchain schema results` prints (built from the typed records that write the file) when the site is "
        "built. `null` stands for what is not available; an object may hold more keys than listed (a renamed "
        "key is kept beside its new name until the next minor version, see the [changelog](../changelog.md)). "
        "`name[]` is an array of such objects.",
        toml=False,
    )


# ------------------------------------------------------------------------------------------------- hooks
_STATE: dict[str, Any] = {}


def on_config(config: MkDocsConfig) -> MkDocsConfig:
    modules = public_modules()
    _STATE["modules"] = modules

    def expand(items: list[Any]) -> bool:
        for i, item in enumerate(items):
            if isinstance(item, dict):
                for title, value in item.items():
                    if value == MODULES_PLACEHOLDER:
                        items[i] = {title: _modules_nav(modules)}
                        return True
                    if isinstance(value, list) and expand(value):
                        return True
        return False

    if config.nav is not None:
        expand(config.nav)
    return config


def on_files(files: Files, config: MkDocsConfig) -> Files:
    modules = _STATE.get("modules") or public_modules()
    pages = {
        f"{API_DIR}/index.md": api_index(modules),
        "reference/cli.md": cli_page(),
        "reference/system-keys.md": keys_page(
            "system",
            "System file keys",
            "Every key of a system file (the TOML that `satchain budget --system`, `simulate --system` and a run "
            "configuration's `[system] file` read), generated from the pydantic models "
            "(`satchain.config.system.ImagingSystem` and its sections) through the JSON Schema that "
            "`satchain schema system` prints, when the site is built. Lengths are in metres; a key's unit is in "
            "its name (`_m`, `_s`, `_hz`, `_deg`, `_px`, `_waves`, `_e`). A range `(0, 1]` excludes 0 and "
            "includes 1. A key not listed here is refused, with the closest valid key named.",
        ),
        "reference/run-keys.md": keys_page(
            "run",
            "Run configuration keys",
            "Every key of a run configuration (`satchain run --config run.toml`; `satchain run --print-config` "
            "prints the defaults), generated from `satchain.config.run.RunConfig` through the JSON Schema that "
            "`satchain schema run` prints, when the site is built. `[system] inline` and the sections of "
            "`[as_built]` take the keys of a [system file](system-keys.md).",
        ),
        "reference/study-keys.md": keys_page(
            "study",
            "Study file keys",
            "Every key of a study file (`satchain study STUDY.toml -o DIR`; see the guide "
            "[Which camera: design and studies](../guide/design-studies.md)), generated from "
            "`satchain.config.study.StudyFile` through the JSON Schema that `satchain schema study` prints, when "
            "the site is built. `[base]` is a [run configuration](run-keys.md), inline (`[base.system]`, "
            '`[base.scene]`, ...) or `file = "run.toml"` (relative to the study file).',
        ),
        "reference/results-json.md": results_page(),
    }
    pages |= {f"{API_DIR}/{mod}.md": module_page(mod) for mod in modules}
    for uri, content in pages.items():
        if files.get_file_from_path(uri) is not None:
            files.remove(files.get_file_from_path(uri))
        files.append(File.generated(config, uri, content=content))
    return files
