"""Test-wide set-up: driver plug-in packages under drivers/ are importable by name."""

import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent
DRIVERS = ROOT / "drivers"
if str(DRIVERS) not in sys.path:
    sys.path.insert(0, str(DRIVERS))
