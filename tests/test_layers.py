"""The package's layers hold: every import-linter contract of pyproject.toml is kept (no import
from a lower layer into a higher one, no import circle), and no source file outgrows 800 lines."""

import subprocess
import sys
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
LONGEST_SOURCE = 800


def test_the_import_contracts_are_kept():
    linter = Path(sys.executable).parent / "lint-imports"
    outcome = subprocess.run(
        [str(linter), "--config", str(REPO / "pyproject.toml"), "--no-cache"],
        cwd=REPO,
        capture_output=True,
        text=True,
    )
    assert outcome.returncode == 0, outcome.stdout + outcome.stderr
    assert "0 broken" in outcome.stdout


def test_no_source_file_is_over_800_lines():
    sources = [*(REPO / "twoball").rglob("*.py"), *(REPO / "app").glob("*.py")]
    long = {
        str(path.relative_to(REPO)): lines
        for path in sources
        if (lines := len(path.read_text().splitlines())) > LONGEST_SOURCE
    }
    assert not long, long
