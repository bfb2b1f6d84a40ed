"""MkDocs hooks that put generated text into two pages at build time.

- ``index.md`` is the repository's README.md, its links made relative to docs/ (the README links
  ``docs/cli.md``; the page beside it is ``cli.md``).
- ``cli.md``'s marker line ``<!-- partscale --help -->`` becomes the reference of every command,
  generated from the commands themselves by Typer's own documentation generator (what
  ``typer partscale.cli utils docs`` prints), each command's examples as a shell block.
"""

from __future__ import annotations

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
CLI_MARKER = "<!-- partscale --help -->"


def cli_reference() -> str:
    """Markdown for ``partscale`` and each subcommand: usage, arguments, options, examples."""
    import typer
    from typer.cli import get_docs_for_click

    from partscale.cli import app

    group = typer.main.get_command(app)
    with typer.Context(group) as ctx:
        text = get_docs_for_click(obj=group, ctx=ctx, name="partscale", indent=1)
    # each command's epilog: "Examples (...):" then indented command lines -> a bash block
    return re.sub(
        r"^(Examples[^\n]*:)\n((?:  \S[^\n]*\n)+)",
        lambda m: (
            m[1]
            + "\n\n```bash\n"
            + "".join(line[2:] + "\n" for line in m[2].splitlines())
            + "```\n"
        ),
        text,
        flags=re.MULTILINE,
    )


def on_page_markdown(markdown: str, page, config, files) -> str:
    if page.file.src_uri == "index.md":
        return re.sub(r"\]\(docs/", "](", (ROOT / "README.md").read_text())
    if page.file.src_uri == "cli.md":
        return markdown.replace(CLI_MARKER, cli_reference())
    return markdown
