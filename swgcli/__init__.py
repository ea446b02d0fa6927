"""Command-line apps (Hydra): swgsim-generate, swgsim-train, swgsim-calibrate, swgsim-paper.

Thin wrappers: each app's work lives in a task function that tests call directly.
"""

from pathlib import Path

REPO_ROOT = Path(__file__).resolve().parent.parent
CONF_DIR = str(REPO_ROOT / "conf")
