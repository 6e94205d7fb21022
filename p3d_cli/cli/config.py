"""``p3d config``: which settings file applies here, and what it sets."""

from __future__ import annotations

import click

from p3d_cli.cli import output
from p3d_cli.cli.options import json_option


@click.command()
@click.argument("inputs", nargs=-1, metavar="[INPUT...]", type=click.Path())
@click.option("--show", is_flag=True, help="Print the settings file and its settings (the default action).")
@json_option
def config(inputs, show, as_json):
    """Show the project settings file p3d would use here, and what it sets.

    p3d looks for p3d.toml, or a pyproject.toml with a [tool.p3d] table, in the working
    directory and then in each parent folder; the first found applies to every command run
    here (--no-config ignores it). With INPUTs, the settings each of them gets (the top level,
    then every [[paths]] entry whose glob matches it) are shown too. The file is checked as
    the commands check it: an error names the file and the key.

    \b
    Examples:
      p3d config --show
      p3d config --show parts/bracket.stl --json
    """
    from p3d_cli.cli.settings_file import load_config

    settings = load_config()
    record = {"file": settings.path, "settings": settings.settings,
              "paths": [{"glob": glob, **values} for glob, values in settings.paths]}
    if inputs:
        record["inputs"] = [{"source": source, "settings": settings.for_source(source)} for source in inputs]
    if as_json:
        click.echo(output.formatted("config", record, "json"))
        return 0
    if settings.path is None:
        click.echo("no settings file (no p3d.toml or [tool.p3d] in pyproject.toml here or in a parent folder)")
        return 0
    click.echo(f"settings file: {settings.path}")
    for key, value in settings.settings.items():
        click.echo(f"  {key} = {output.dumps(value)}")
    for index, (glob, values) in enumerate(settings.paths):
        click.echo(f"  paths[{index}]: glob = {output.dumps(glob)}")
        for key, value in values.items():
            click.echo(f"    {key} = {output.dumps(value)}")
    for entry in record.get("inputs", ()):
        shown = ", ".join(f"{k} = {output.dumps(v)}" for k, v in entry["settings"].items()) or "none"
        click.echo(f"{output.shown_name(entry['source'])}: {shown}")
    return 0
