"""Helpers of the tests that describe systems as scene data (dicts): build one, run it."""
from flexsym.scenes.system_scene import system_from_dict


_derived: dict = {}  # fingerprint -> the derivation built() generated a folder from


def with_model(data: dict, model) -> dict:
    """Scene data with every beam given `model` (in place; returned)."""
    for b in data["body"]:
        if b["kind"] == "beam":
            b["model"] = model
    return data


def built(data: dict, model: str | None = None):
    """The built system of scene data (every beam given `model` when one is named). A folder
    generated here keeps its derivation for derivation(data)."""
    from flexsym.codegen import sysgen
    from flexsym.toolchain.pipeline import prepare_system

    if model is not None:
        with_model(data, model)
    system = system_from_dict(data, name=data["system"]["name"])
    originals = sysgen.derive_spatial, sysgen.derive_system

    def keep(derive):
        def derived(*args, **kw):
            der = derive(*args, **kw)
            _derived[sysgen.fingerprint(system)] = der
            return der
        return derived
    sysgen.derive_spatial, sysgen.derive_system = map(keep, originals)
    try:
        return prepare_system(system, log=lambda m: None)
    finally:
        sysgen.derive_spatial, sysgen.derive_system = originals


def derivation(data: dict):
    """The derivation of scene data's system: the one its generated C came from when built()
    generated it in this process (a spatial one with sections takes up to a minute), else made
    now."""
    from flexsym.codegen import sysgen
    from flexsym.physics.assemble import derive_system
    from flexsym.physics.spatial import derive_spatial

    system = system_from_dict(data, name=data["system"]["name"])
    der = _derived.get(sysgen.fingerprint(system))
    if der is None:
        der = derive_spatial(system) if system.dimension == 3 else derive_system(system)
    return der


def run_ok(built_system, **kw):
    """run_built, asserting that the run finished."""
    from flexsym.toolchain.run import run_built

    r = run_built(built_system, **kw)
    assert r.ok, r.status
    return r


def refused_in_one_line(capsys, path, says: str) -> None:
    """`flexsym run path` (in-process: the CLI's own main) is refused in one line naming the
    file and saying `says`, exit 2, nothing written."""
    from flexsym.apps.cli import main

    out = path.parent / "out.csv"
    code = main(["run", str(path), "--out", str(out)])
    std = capsys.readouterr()
    assert code == 2, std.err
    assert std.out == "" and std.err.count("\n") == 1 and f"flexsym: error: {path}: " in std.err, std
    assert says in std.err, std.err
    assert not out.exists()


def edited_scene(tmp_path, what: str, scene, edits):
    """A copy of the scene file with each (old, new) edit made once (each old is there once)."""
    text = scene.read_text()
    for old, new in edits:
        assert text.count(old) == 1, what
        text = text.replace(old, new)
    path = tmp_path / "bad.toml"
    path.write_text(text)
    return path


def scene_text_runs(tmp_path, capsys, text: str) -> None:
    """`flexsym run` of a scene given as text finishes and writes its CSV (the base of a set of
    malformed scenes: each refusal is then its edit's)."""
    from flexsym.apps.cli import main

    path, out = tmp_path / "good.toml", tmp_path / "out.csv"
    path.write_text(text)
    assert main(["run", str(path), "--out", str(out)]) == 0, capsys.readouterr().err
    assert out.exists()


def scene_text_refused(tmp_path, capsys, text: str, says: str) -> None:
    """refused_in_one_line for a scene given as text."""
    path = tmp_path / "bad.toml"
    path.write_text(text)
    refused_in_one_line(capsys, path, says)
