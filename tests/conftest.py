"""Test settings: under CI (CI=true) hypothesis runs derandomised, so a submission's CI run
tries the same examples as every other; locally it keeps exploring new ones."""

import os

from hypothesis import settings

settings.register_profile("ci", derandomize=True, deadline=None)
if os.environ.get("CI", "").lower() == "true":
    settings.load_profile("ci")
