"""Every shell block of the README and the documentation runs as written (marker `docs`; CI
runs them after the suite: `python -m pytest -q -m docs tests/test_docs_commands.py`).

Each ```bash block is run as one bash script (`set -e`) from a scratch folder that holds the
repository's `scenes/` and `docs/` (the validation report's scripts), as a user runs it from the
repository root. A command followed by a
`# flexsym: error ...` line is a documented refusal: it must exit 2 with that message. Blocks
that say they take minutes (the validation report's studies) carry the marker `study` as well
and run only when asked (`-m study`); blocks that create the virtual environment are the
README's quick start, which `.ci/run` runs verbatim."""
from __future__ import annotations

import os
import re
import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
LONG = re.compile(r"#.*(minute|hour)")


def shell_blocks() -> list[tuple[str, str]]:
    """(page:line, script) for every ```bash block of README.md and docs/**/*.md."""
    blocks = []
    for page in [ROOT / "README.md", *sorted((ROOT / "docs").rglob("*.md"))]:
        if "_build" in page.parts:
            continue
        lines, start, lang = page.read_text().splitlines(), None, None
        for i, line in enumerate(lines):
            if line.startswith("```"):
                if lang is None:
                    lang, start = line[3:].strip() or "text", i + 1
                else:
                    if lang in ("bash", "sh"):
                        blocks.append((f"{page.relative_to(ROOT)}:{start}", "\n".join(lines[start:i])))
                    lang = None
    return blocks


def _split_refusals(script: str) -> tuple[str, list[tuple[str, str]]]:
    """The script without its documented refusals, and the refusals (command, message)."""
    lines, keep, refusals = script.splitlines(), [], []
    for i, line in enumerate(lines):
        if line.startswith("# flexsym: error"):
            continue
        if i + 1 < len(lines) and lines[i + 1].startswith("# flexsym: error"):
            message = lines[i + 1][len("# flexsym: error:"):].split("(exit")[0].strip()
            refusals.append((line.strip(), message))
        else:
            keep.append(line)
    return "\n".join(keep), refusals


def _cases():
    for where, script in shell_blocks():
        if "python3 -m venv" in script:
            continue  # the README's quick start: .ci/run runs it verbatim
        marks = [pytest.mark.docs] + ([pytest.mark.study] if LONG.search(script) else [])
        yield pytest.param(script, id=where, marks=marks)


@pytest.fixture(scope="module")
def workdir(tmp_path_factory):
    d = tmp_path_factory.mktemp("docs-commands")
    (d / "scenes").symlink_to(ROOT / "scenes")
    return d


@pytest.mark.parametrize("script", list(_cases()))
def test_documented_block_runs(script, workdir, tmp_path):
    env = dict(os.environ, MPLBACKEND="Agg")
    run_dir = tmp_path / "cwd"
    run_dir.mkdir()
    (run_dir / "scenes").symlink_to(ROOT / "scenes")
    (run_dir / "docs").symlink_to(ROOT / "docs")
    body, refusals = _split_refusals(script)
    r = subprocess.run(["bash", "-e", "-c", body], cwd=run_dir, env=env, capture_output=True, text=True,
                       timeout=1800)
    assert r.returncode == 0, f"exit {r.returncode}\n{body}\n--- stderr:\n{r.stderr[-3000:]}"
    for cmd, message in refusals:
        r = subprocess.run(["bash", "-c", cmd], cwd=run_dir, env=env, capture_output=True, text=True,
                           timeout=300)
        assert r.returncode == 2 and message in r.stderr, (cmd, r.returncode, r.stderr[-2000:])


def test_every_block_is_found():
    """The extraction sees the documented blocks (a parser that finds nothing would pass)."""
    found = shell_blocks()
    assert len(found) >= 20
    assert any("flexsym run scenes/four_bar.toml" in s for _, s in found)


def test_readme_links_and_pictures_exist():
    """The README is read on its own (not by Sphinx, which checks the site's links): every
    relative link and picture it shows is a file of the repository."""
    text = (ROOT / "README.md").read_text()
    targets = re.findall(r"\]\(([^)\s#]+)(?:#[^)]*)?\)", text)
    assert len(targets) >= 10
    missing = [t for t in targets if not t.startswith("http") and not (ROOT / t).exists()]
    assert not missing, missing


def test_readme_example_runs_and_reads_its_columns(tmp_path):
    """The README's Python example, run as written: the arm falls (y_tip reaches about -L) and
    the clamp carries a bending moment."""
    code = (ROOT / "README.md").read_text().split("```python\n", 1)[1].split("```", 1)[0]
    r = subprocess.run(["python", "-c", code], cwd=tmp_path, capture_output=True, text=True,
                       timeout=600, env=dict(os.environ, MPLBACKEND="Agg"))
    assert r.returncode == 0, r.stderr[-2000:]
    status, y_min, m_max = re.fullmatch(r"(\S+) (\S+) m (\S+) N m\n", r.stdout).groups()
    assert status == "ok" and -0.51 < float(y_min) < -0.45 and float(m_max) > 0.0
