"""The package's layers (pyproject.toml, [tool.importlinter]): no module imports from a layer
above its own, checked on every import statement, function-level ones included."""
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def test_import_layers_kept():
    r = subprocess.run([sys.executable, "-c", "from importlinter.cli import lint_imports_command; "
                        "lint_imports_command()"], cwd=ROOT, capture_output=True, text=True)
    assert r.returncode == 0, r.stdout[-3000:] + r.stderr[-2000:]
    assert "0 broken" in r.stdout


def test_every_module_sits_in_a_layer():
    """No module outside the layers (the contract cannot see what it does not list)."""
    pkg = ROOT / "flexsym"
    loose = [p.name for p in pkg.glob("*.py") if p.name != "__init__.py"]
    assert not loose, f"modules outside a layer: {loose}"


def test_every_package_is_installed():
    """pyproject's explicit package list names every folder of flexsym (an editable install finds
    an unlisted one; a wheel would leave it out, and the imports from it would fail)."""
    import tomllib

    listed = set(tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]["packages"])
    found = {".".join(p.parent.relative_to(ROOT).parts) for p in (ROOT / "flexsym").rglob("__init__.py")}
    assert found <= listed, f"not in pyproject's packages: {sorted(found - listed)}"
