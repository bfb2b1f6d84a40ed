"""How every subcommand's ``--help`` reads, and the old option spellings still accepted.

One home for the CLI's help conventions:

- metavars are words (``N``, ``FILE``, ``VIEW``), never Python types; flags show none;
- a default is shown one way: typer's ``[default: X]`` after the help (``show_default`` text where
  the value is worked out at run time), never in the help's prose;
- every subcommand ends with examples (:data:`EXAMPLES`) that run, in order, in one folder, on the
  table shipped with the package (``python -m partscale.data table`` prints its path) and, for
  ``complete``, the frame of it shipped beside (``python -m partscale.data table-scan``);
- an old option spelling keeps working for one release (:data:`DEPRECATED`), with one note line.
"""

from __future__ import annotations

import re
import sys

import typer
from typer.core import TyperCommand, TyperGroup

#: Examples per subcommand; run in this order in one folder they make the files the later ones
#: read (``tests/test_cli_help.py`` runs them all).
EXAMPLES: dict[str, list[str]] = {
    "import": [
        'partscale import "$(python -m partscale.data table)" -o table.csdf.npz --res 128',
    ],
    "info": ["partscale info table.csdf.npz"],
    "segment": ["partscale segment table.csdf.npz -o table.csdf.npz"],
    "suggest": ["partscale suggest table.csdf.npz --axis x --png table_zones.png"],
    "scale": [
        "partscale scale table.csdf.npz -o table_longer.csdf.npz --axis x --zone 35% 65% --by 40cm",
        "partscale scale table.csdf.npz -o table_tall.csdf.npz --axis y --zone 20% 80% --to 110%",
        'partscale scale "$(python -m partscale.data table)" -o table_longer.glb --axis x '
        "--zone 35% 65% --by 20in",
        "partscale scale table.csdf.npz -o table_wide_top.csdf.npz --radial --center 0 0 "
        "--sides 4 --zone 20% 70% --by 10cm",
    ],
    "fit": ["partscale fit table.csdf.npz -o table_fit.csdf.npz --size 3m = 120%"],
    "export": [
        "partscale export table_longer.csdf.npz --mesh table_longer.ply",
        "partscale export table_longer.csdf.npz --mesh table_small.glb --grid 64 --faces 2000",
    ],
    "render": [
        "partscale render table_longer.csdf.npz -o table_longer.png --view iso",
        "partscale render table.csdf.npz -o table_parts.png --parts --pixels 256",
        "partscale render table_longer.glb -o table_longer_mesh.png",
    ],
    "complete": [
        'partscale complete --depth "$(python -m partscale.data table-scan)/depth.png" '
        '--color "$(python -m partscale.data table-scan)/color.jpg" '
        '--intrinsics "$(python -m partscale.data table-scan)/intrinsics.json" '
        "-o table_completed.csdf.npz --upright",
        "partscale fit table_completed.csdf.npz -o table_completed_longer.csdf.npz --size 120% = =",
    ],
    "eval": ["partscale eval --original table.csdf.npz --edited table_longer.csdf.npz"],
    "batch": [
        'partscale batch "$(python -m partscale.data table)" -o batch_out --res 64 --segment '
        "--size 2m = = --export glb --render",
    ],
    "editor": ["partscale editor table.csdf.npz"],
}

#: Old option spellings, per subcommand: still accepted for one release, with a note.
DEPRECATED: dict[str, dict[str, str]] = {
    "import": {"--colors": "--color"},
    "export": {"--size": "--grid"},
    "render": {"--size": "--pixels"},
    "batch": {"--fit": "--size"},
    "eval": {"--out": "--output"},
}


def epilog(command: str) -> str:
    """The ``--help`` epilog of ``command``: its examples, one per line."""
    lines = "\n".join(f"  {e}" for e in EXAMPLES[command])
    sample = "table-scan" if command == "complete" else "table"
    what = "a depth frame of the table" if command == "complete" else "the table"
    return (
        f"Examples (on {what} shipped with partscale; `python -m partscale.data {sample}` "
        f"prints its path):\n{lines}"
    )


def _unwrap(text: str | None) -> str | None:
    """Paragraphs as single lines (typer's rich help keeps a docstring's line breaks)."""
    if not text:
        return text
    import inspect

    paragraphs = inspect.cleandoc(text).split("\n\n")
    return "\n\n".join(p if p.startswith("\b") else " ".join(p.split()) for p in paragraphs)


def _tidy(params) -> None:
    """Flags take no value: no metavar (typer would show ``<bool>``); an argument's metavar says
    what it is (typer would add its Python type); a default worked out at run time is shown as
    written (typer would wrap it in parentheses)."""
    from typer.core import TyperArgument

    for p in params:
        if getattr(p, "is_flag", False):
            p.metavar = ""
        if isinstance(p, TyperArgument):
            p.display_type_rich = _no_type  # type: ignore[method-assign]
        if isinstance(getattr(p, "show_default", None), str):
            p._get_default_string = _as_written(p.show_default)


def _no_type(ctx) -> None:
    return None


def _as_written(text: str):
    def default_string(**_kwargs) -> str:
        return text

    return default_string


def _tidy_command(cmd: TyperCommand | TyperGroup) -> None:
    """What every command and the group share: unwrapped help, the parameters tidied."""
    cmd.help = _unwrap(cmd.help)
    _tidy(cmd.params)


def _no_metavar(option):
    if option is not None:
        option.metavar = ""
    return option


class Command(TyperCommand):
    """A subcommand with partscale's help conventions (see the module)."""

    def __init__(self, *args, **kwargs) -> None:
        super().__init__(*args, **kwargs)
        _tidy_command(self)

    def get_help_option(self, ctx):
        return _no_metavar(super().get_help_option(ctx))


class Group(TyperGroup):
    """The ``partscale`` group with the same conventions."""

    def __init__(self, *args, **kwargs) -> None:
        super().__init__(*args, **kwargs)
        _tidy_command(self)

    def get_help_option(self, ctx):
        return _no_metavar(super().get_help_option(ctx))


def command(app: typer.Typer, name: str, fn) -> None:
    """Register ``fn`` as subcommand ``name`` with its examples."""
    app.command(name, cls=Command, epilog=epilog(name))(fn)


_OPTION = re.compile(r"^(--[a-z][a-z-]*)(=.*)?$")


def accept_deprecated(argv: list[str]) -> list[str]:
    """``argv`` with each old option spelling of its subcommand replaced by the new one, and one
    note line on stderr per old spelling used."""
    words = [a for a in argv if not a.startswith("-")]
    if not words or words[0] not in DEPRECATED:
        return argv
    command = words[0]
    table = DEPRECATED[command]
    out = list(argv)
    start = argv.index(command) + 1
    for i in range(start, len(out)):
        if out[i] == "--":  # the rest are arguments, whatever they look like
            break
        m = _OPTION.match(out[i])
        if m is None or m[1] not in table:
            continue
        new = table[m[1]]
        out[i] = new + (m[2] or "")
        sys.stderr.write(
            f"partscale: note: {command} {m[1]} is now {new}; the old spelling goes in the next "
            "release\n"
        )
    return out


def in_cli_terms(exc: BaseException, argv: list[str]) -> str:
    """``exc``'s message with the library's parameter names in the command line's spelling.

    The library names a parameter as its function takes it (``res``, ``world_size``); the
    subcommand being run spells it as an option (``--res``, ``--world-size``). Translated:
    labels before the message's ``expected`` (``rank: expected ...``, ``a.glb: iso: ...``) that
    name an option of the subcommand, and the parameters the error lists
    (:attr:`partscale.errors.InputError.params`) as whole words outside file paths.
    """
    message = str(exc)
    flags = _flags(argv)
    if not flags:
        return message
    head, sep, tail = message.partition("expected")
    head = ": ".join(flags.get(label, label) for label in head.split(": "))
    message = head + sep + tail
    for name in getattr(exc, "params", ()):
        if name in flags:
            word = rf"(?<![\w./-]){re.escape(name)}(?![\w/-]|\.\w)"
            message = re.sub(word, flags[name], message)
    return message


def _flags(argv: list[str]) -> dict[str, str]:
    """{parameter name: its long option} of the subcommand ``argv`` runs ({} for none)."""
    words = [a for a in argv if not a.startswith("-")]
    if not words:
        return {}
    from . import app

    group = typer.main.get_command(app)
    cmd = getattr(group, "commands", {}).get(words[0])
    if cmd is None:
        return {}
    out = {}
    for p in cmd.params:
        longs = [o for o in p.opts if o.startswith("--")]
        if p.name and longs and p.param_type_name == "option":
            out[p.name] = longs[0]
    return out
