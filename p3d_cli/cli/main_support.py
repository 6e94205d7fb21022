"""Helpers the commands and the group share (kept apart from main.py to avoid import cycles)."""

from __future__ import annotations

import click


def error_line(text: str) -> None:
    """Print one diagnostic line to stderr in p3d's format: ``p3d: error: <text>``."""
    click.echo(f"p3d: error: {text}", err=True)
