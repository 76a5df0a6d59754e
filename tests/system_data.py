"""Helpers of the tests that describe systems as scene data (dicts): build one, run it."""
from flexsym.scenes.system_scene import system_from_dict


def built(data: dict, model: str | None = None):
    """The built system of scene data (every beam given `model` when one is named)."""
    from flexsym.toolchain.pipeline import prepare_system

    if model is not None:
        for b in data["body"]:
            if b["kind"] == "beam":
                b["model"] = model
    return prepare_system(system_from_dict(data, name=data["system"]["name"]), log=lambda m: None)


def run_ok(built_system, **kw):
    """run_built, asserting that the run finished."""
    from flexsym.toolchain.run import run_built

    r = run_built(built_system, **kw)
    assert r.ok, r.status
    return r
