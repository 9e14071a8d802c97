"""Models declare their plug-ins and are discovered (issue 41, item 4).

The built-in models are the public modules and packages of ``workbench.models`` (no list to
edit); a model names its overview figure, its exudyn builder and the model whose measured first
compile stands in for its own, and the plot, verification and console code ask the model; the
hooks every mechanism shares are one definition, compiled as functions of each mechanism's
module.
"""

from __future__ import annotations

import importlib
import pkgutil
import subprocess
import sys

import pytest

import workbench
import workbench.models as models
from workbench.models import Effect, Model, get_model, register


def _registered_in_the_package() -> set[str]:
    """The names of the models that the package's modules register, every module imported."""
    for m in pkgutil.walk_packages(models.__path__, models.__name__ + "."):
        importlib.import_module(m.name)
    return {n for n, cls in models._REGISTRY.items() if cls.__module__.startswith("workbench.")}


def test_discovery_finds_every_built_in_model_and_no_library():
    assert set(models.available_models()) >= _registered_in_the_package()
    assert set(models._builtin()) == _registered_in_the_package()
    for library in ("contact", "friction", "no_events"):
        assert library not in models.available_models()


FAKE_BUILTIN = """
from workbench.models import Model, Parameter, Quantity, register


@register
class Dropped(Model):
    name = "dropped_in"
    hooks = "workbench.models.duffing"
    parameters = (Parameter("a", 1.0, "1", "a"),)
    fixed_states = (Quantity("x", "1", "x"),)
"""


def test_a_model_module_put_in_the_package_is_found_without_editing_a_list(tmp_path, monkeypatch):
    (tmp_path / "dropped_in.py").write_text(FAKE_BUILTIN)
    monkeypatch.setattr(models, "__path__", [*models.__path__, str(tmp_path)])
    monkeypatch.setattr(models, "_REGISTRY", dict(models._REGISTRY))
    monkeypatch.delitem(sys.modules, "workbench.models.dropped_in", raising=False)
    models._builtin.cache_clear()
    try:
        assert "dropped_in" in models.available_models()
        assert get_model("dropped_in").parameter("a").default == 1.0
        with pytest.raises(ValueError, match="taken by the built-in model"):
            register(type("Impostor", (Model,), {"name": "dropped_in"}))
    finally:
        models._builtin.cache_clear()
        sys.modules.pop("workbench.models.dropped_in", None)


def test_the_mechanisms_plug_ins_resolve_and_importing_a_model_imports_no_upper_layer():
    from workbench.plot._ninebar import ninebar_overview
    from workbench.plot._slider_crank import slider_crank_overview
    from workbench.verification import verifiable_models
    from workbench.verification._mechanisms import ninebar_mechanism, slider_crank_mechanism

    nine, crank = get_model("ninebar"), get_model("slider_crank")
    assert nine.plugin("overview_figure") is ninebar_overview
    assert crank.plugin("overview_figure") is slider_crank_overview
    assert nine.plugin("verification") is ninebar_mechanism
    assert crank.plugin("verification") is slider_crank_mechanism
    for name in models.available_models():
        for kind in ("overview_figure", "verification"):
            found = get_model(name).plugin(kind)
            assert found is None or callable(found), (name, kind)
    assert verifiable_models() == ("ninebar", "slider_crank")
    with pytest.raises(ValueError, match="'drawing' is not one of"):
        nine.plugin("drawing")
    # the dotted names are imported by the layer that uses them, never by the model
    code = (
        "import sys, workbench.models as m\n"
        "for n in m.available_models(): m.get_model(n)\n"
        "print(sorted({k.split('.')[1] for k in sys.modules if k.startswith('workbench.')}),"
        " 'matplotlib' in sys.modules)"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True
    ).stdout
    for layer in ("plot", "verification", "cli", "campaign", "run", "archive"):
        assert f"'{layer}'" not in out, out
    assert out.strip().endswith("False"), out


# A mechanism declared in a test: its overview figure and its compile time come from the model
# alone (the Duffing oscillator's hooks, so that nothing new is compiled).
def fake_overview(ds):
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots()
    ax.plot(ds.time, ds.x)
    fig.suptitle("the fake mechanism's overview")
    return fig


def fake_builder(scene):
    return ("built", scene.model)


class FakeMechanism(type(get_model("duffing"))):
    name = "fake_mechanism"
    effects = (Effect("friction", "none", "choice", "friction law", ("none",)),)
    overview_figure = f"{__name__}:fake_overview"
    verification = f"{__name__}:fake_builder"
    compile_stand_in = "ninebar"


@pytest.fixture
def fake(monkeypatch):
    monkeypatch.setattr(models, "_REGISTRY", dict(models._REGISTRY))
    register(FakeMechanism)
    return FakeMechanism.name


def test_a_new_mechanism_gets_its_overview_figure_through_the_model(fake, tmp_path):
    from workbench.plot import run_figure_names, run_figures

    assert f"{fake}_overview.png" in run_figure_names(fake, 2)
    assert "duffing_overview.png" not in run_figure_names("duffing", 2)
    ds = workbench.simulate({"model": {"name": fake}, "run": {"cycles": 2}})
    written = run_figures(ds, tmp_path)
    assert tmp_path / f"{fake}_overview.png" in written
    assert (tmp_path / f"{fake}_overview.png").stat().st_size > 0


def test_a_new_mechanism_gets_its_compile_time_and_verification_through_the_model(fake):
    from workbench.cli._console import compile_notice
    from workbench.verification._mechanisms import build_mechanism, check_scene

    notice = compile_notice(fake)
    assert f"compiling the {fake} kernel (first run only; measured for the ninebar kernel" in (
        notice
    )
    assert "measured for the duffing kernel" in compile_notice("lorenz")  # the default
    scene = workbench.load_scene({"model": {"name": fake}})
    check_scene(scene)  # a model that names its builder is verifiable
    assert build_mechanism(scene) == ("built", fake)


def test_an_unknown_model_has_no_overview_and_the_default_stand_in():
    from workbench.campaign._warm import compile_record
    from workbench.plot._base import overview

    assert overview("not_a_model") is None and overview(None) is None
    assert compile_record("not_a_model")[0] == "duffing"


def test_the_hooks_every_mechanism_shares_are_one_definition_compiled_per_mechanism():
    from workbench.models import _mechanism_hooks as shared
    from workbench.models.ninebar import _dynamics as nine
    from workbench.models.slider_crank import _dynamics as crank

    for name in ("evaluate_many", "rhs_reference", "event_values", "apply_event"):
        a, b = getattr(nine, name), getattr(crank, name)
        assert a.py_func.__code__ is b.py_func.__code__ is getattr(shared, name).__code__
        assert a.py_func.__module__ == nine.__name__ and b.py_func.__module__ == crank.__name__
        # each mechanism's compiled code is cached apart, keyed by its own module's code
        assert a._cache._cache_path != b._cache._cache_path
        assert a.py_func.__globals__["evaluate"] is nine.evaluate
        assert b.py_func.__globals__["N_JOINTS"] == 1 and a.py_func.__globals__["N_JOINTS"] == 2


def test_a_model_declares_nothing_by_default():
    m = type("Plain", (Model,), {"name": "plain"})()
    assert m.plugin("overview_figure") is None and m.plugin("verification") is None
    assert Model.compile_stand_in == "duffing"
    assert get_model("ninebar").compile_stand_in == "slider_crank"  # a mechanism's default
