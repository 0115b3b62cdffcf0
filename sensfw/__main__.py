"""``python -m sensfw`` runs the command line."""

from .cli import app

app()
