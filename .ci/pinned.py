"""Exit 1, naming each package, unless this Python holds exactly the versions pinned (==) in
the constraints file given: pip takes a constraint only for what it installs, so a pin that
nothing required would pass unseen."""

import importlib.metadata
import sys
from pathlib import Path

lines = Path(sys.argv[1]).read_text(encoding="utf-8").splitlines()
pins = [line.split("#")[0].strip().split("==") for line in lines]
wrong = []
for name, version in (pin for pin in pins if len(pin) == 2):
    try:
        found = importlib.metadata.version(name)
    except importlib.metadata.PackageNotFoundError:
        found = "not installed"
    if found != version:
        wrong.append(f"{name} {found} (pinned {version})")
if wrong:
    sys.exit("not the pinned versions: " + ", ".join(wrong))
print("pinned versions: " + ", ".join(f"{p[0]} {p[1]}" for p in pins if len(p) == 2))
