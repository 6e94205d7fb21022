"""``python -m p3d_cli`` runs the ``p3d`` command line."""

from p3d_cli.cli.main import run

run()
