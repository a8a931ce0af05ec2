"""Docs that are generated from code stay in sync with it."""
from __future__ import annotations

import re
import subprocess
import sys

from conftest import ROOT


def test_calc_table_is_current():
    r = subprocess.run([sys.executable, str(ROOT / "scripts" / "gen_docs_tables.py"), "--check"])
    assert r.returncode == 0, "docs/calc_rods.md is stale: run python scripts/gen_docs_tables.py"


def test_cli_reference_is_current():
    r = subprocess.run([sys.executable, str(ROOT / "scripts" / "gen_cli_docs.py"), "--check"])
    assert r.returncode == 0, "docs/cli.md is stale: run python scripts/gen_cli_docs.py"


def test_readme_first_lines_give_the_two_commands():
    lines = (ROOT / "README.md").read_text().splitlines()[:8]
    text = "\n".join(lines)
    assert "pip install -e" in text and "rodlab demo" in text
    assert 'pip install -e ".[test,cad,viz]"' in text and "python -m pytest" in text
    ci = (ROOT / ".ci" / "run").read_text()
    found = re.search(r"python -m pytest [^\n]*", ci)
    assert found, ".ci/run runs no `python -m pytest ...` line"
    pytest_line = found.group(0)                                           # CI runs the README's test command
    assert pytest_line.startswith('python -m pytest -m "not slow"') and text.rstrip().endswith(pytest_line + "\n```")
