"""Shared fixtures: an isolated build cache, derivations and compiled models per variant."""
from __future__ import annotations

import os

import pytest


@pytest.fixture(scope="session", autouse=True)
def isolated_cache(tmp_path_factory):
    """Builds and custom variants go to a fresh cache, as on a new machine."""
    path = tmp_path_factory.mktemp("flexsym-cache")
    old = os.environ.get("FLEXSYM_CACHE")
    os.environ["FLEXSYM_CACHE"] = str(path)
    yield path
    if old is None:
        os.environ.pop("FLEXSYM_CACHE", None)
    else:
        os.environ["FLEXSYM_CACHE"] = old


_derivations: dict = {}
_models: dict = {}


@pytest.fixture(scope="session")
def derivation():
    from flexsym.codegen.derive import derive
    from flexsym.model.variant import builtin

    def get(name):
        spec = builtin(name)
        if spec.name not in _derivations:
            _derivations[spec.name] = derive(spec)
        return _derivations[spec.name]

    return get


@pytest.fixture(scope="session")
def model(isolated_cache):
    from flexsym.toolchain.pipeline import compiled
    from flexsym.model.variant import builtin

    def get(name):
        spec = builtin(name)
        if spec.name not in _models:
            _models[spec.name] = compiled(spec)
        return _models[spec.name]

    return get


@pytest.fixture(scope="session")
def simulate(isolated_cache):
    """simulate(variant, **run options) -> RunResult (builds once per variant)."""
    from flexsym.toolchain.pipeline import prepare
    from flexsym.toolchain.run import run_built
    from flexsym.model.variant import builtin

    builds = {}

    def run(name, **kw):
        spec = builtin(name)
        if spec.name not in builds:
            builds[spec.name] = prepare(spec)
        return run_built(builds[spec.name], **kw)

    return run


BUILTIN_NAMES = ["linear", "geometric", "geometric_sine", "foreshortening"]
