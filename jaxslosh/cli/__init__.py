"""The command line (`jaxslosh`, `python -m jaxslosh`): one module per command; main.py dispatches."""
from .main import main

__all__ = ["main"]
