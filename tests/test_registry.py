"""Plugin discovery: built-ins, entry points (good, broken, duplicate), blocking, contracts."""

import importlib.metadata
import textwrap
import types

import pytest

import softcell
from softcell.analysis.options import ANALYSIS_OPTIONS
from softcell.components.contracts import StopGoDetector
from softcell.components.registry import KINDS, PluginWarning, Registry, default_registry
from softcell.errors import ConfigError, RegistryError
from softcell.model.parameters import MODEL_PARAMETERS, unit_problem
from softcell.testing import registered


def fake_entry_points(tmp_path, monkeypatch, **plugins):
    """Install a fake distribution 'softcell-fake' whose entry points name test modules."""
    info = tmp_path / "softcell_fake-1.2.dist-info"
    info.mkdir()
    (info / "METADATA").write_text("Metadata-Version: 2.1\nName: softcell-fake\nVersion: 1.2\n")
    lines = "\n".join(f"{name} = fakeplugins.{module}" for name, module in plugins.items())
    (info / "entry_points.txt").write_text(f"[softcell]\n{lines}\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    return [
        ep
        for ep in importlib.metadata.entry_points(group="softcell")
        if ep.dist.name == "softcell-fake"
    ]


def test_builtins_register_through_the_hooks():
    registry = Registry(entry_points=[])
    assert set(KINDS.values()) == {
        "energy_term",
        "driving_protocol",
        "friction_law",
        "integrator",
        "stopgo_detector",
        "pair_term",
        "bot_interaction",
    }
    assert registry.names("bot_interaction") == ["alignment", "bot_repulsion"]
    assert registry.names("friction_law") == ["coulomb", "viscous"]
    assert "arena" in registry.names("energy_term")
    entry = registry.entries("stopgo_detector")[0]
    assert entry.component.name == "threshold"
    assert entry.origin.startswith("built-in")


def test_good_entry_point_is_loaded_with_its_distribution(tmp_path, monkeypatch):
    eps = fake_entry_points(tmp_path, monkeypatch, good="good")
    registry = Registry(entry_points=eps)
    assert registry.names("stopgo_detector") == ["fake_hysteresis", "threshold"]
    origin = registry.entries("stopgo_detector")[0].origin
    assert "softcell-fake 1.2" in origin and "good = fakeplugins.good" in origin
    assert "fake_level" in registry.parameter_specs()


def test_broken_entry_point_warns_with_its_distribution_and_is_skipped(tmp_path, monkeypatch):
    eps = fake_entry_points(tmp_path, monkeypatch, good="good", broken="broken")
    with pytest.warns(
        PluginWarning,
        match=r"'broken' from distribution softcell-fake 1\.2.*"
        r"ImportError: this fake plugin needs",
    ):
        registry = Registry(entry_points=eps)
    assert registry.names("stopgo_detector") == ["fake_hysteresis", "threshold"]
    assert [name for name, _ in registry.skipped] == ["broken"]


@pytest.mark.parametrize(
    "module, message",
    [
        ("misspelt", "unknown hook 'softcell_energy_term'"),
        ("malformed", "description must be one non-empty line.*abstract methods not implemented"),
    ],
)
def test_malformed_plugins_are_skipped_loudly(tmp_path, monkeypatch, module, message):
    eps = fake_entry_points(tmp_path, monkeypatch, bad=module)
    with pytest.warns(PluginWarning, match=message):
        registry = Registry(entry_points=eps)
    assert registry.names("stopgo_detector") == ["threshold"]


def test_a_component_whose_unit_is_no_unit_is_skipped_alone(tmp_path, monkeypatch):
    eps = fake_entry_points(tmp_path, monkeypatch, units="badunits")
    with pytest.warns(PluginWarning) as caught:
        registry = Registry(entry_points=eps)
    (message,) = [str(w.message) for w in caught]
    assert "the stop/go detector Bananas of softcell plugin 'units'" in message
    assert "softcell-fake 1.2" in message
    assert "parameter 'banana_level': unit 'bananas' does not parse as UDUNITS-2" in message
    assert "parameter 'blank_level': unit '' is not a UDUNITS-2 unit string" in message
    assert registry.names("stopgo_detector") == ["plain", "threshold"]


@pytest.mark.parametrize(
    ("unit", "ok"),
    [
        ("1", True),
        ("N cm-2", True),
        ("cm s-1", True),
        ("rad", True),
        ("N s cm-2", True),
        ("", False),
        (None, False),
        ("bananas", False),
        ("unknown", False),
        (" ", False),
    ],
)
def test_units_parse_as_udunits(unit, ok):
    assert (unit_problem(unit) is None) == ok


def test_every_builtin_unit_parses():
    specs = [
        *MODEL_PARAMETERS.values(),
        *ANALYSIS_OPTIONS.values(),
        *Registry(entry_points=[]).parameter_specs().values(),
    ]
    assert [(s.name, s.unit) for s in specs if unit_problem(s.unit)] == []


def test_duplicate_name_is_an_error_naming_both_origins(tmp_path, monkeypatch):
    eps = fake_entry_points(tmp_path, monkeypatch, dup="duplicate")
    with pytest.raises(RegistryError) as info:
        Registry(entry_points=eps)
    message = str(info.value)
    assert "'threshold'" in message
    assert "built-in (softcell.builtins.threshold)" in message
    assert "softcell-fake 1.2 (entry point dup = fakeplugins.duplicate)" in message


def test_disable_env_blocks_plugins_by_name(tmp_path, monkeypatch):
    eps = fake_entry_points(tmp_path, monkeypatch, dup="duplicate", broken="broken")
    monkeypatch.setenv("SOFTCELL_DISABLE_PLUGINS", "threshold, broken")
    registry = Registry(entry_points=eps)  # neither the clash nor the broken import happens
    assert registry.entries("stopgo_detector")[0].origin.startswith("softcell-fake") is False
    assert "softcell-fake" in registry.entries("stopgo_detector")[0].origin


def test_unknown_component_name_lists_what_exists():
    with pytest.raises(ConfigError, match="did you mean 'threshold'.*available: threshold"):
        Registry(entry_points=[]).get("stopgo_detector", "treshold")
    with pytest.raises(ConfigError, match="no component kind"):
        Registry(entry_points=[]).get("detector", "threshold")


def test_plugin_registered_for_one_test():
    class Always(StopGoDetector):
        name = "always_go"
        description = "every sample is go"

        def label(self, speed, interval):
            raise NotImplementedError

    plugin = types.SimpleNamespace(softcell_stopgo_detectors=softcell.hookimpl(lambda: [Always]))
    with registered(plugin):
        assert default_registry().get("stopgo_detector", "always_go") is Always
    assert "always_go" not in default_registry().names("stopgo_detector")


def test_hook_docs_mention_units():
    from softcell.components import hookspecs

    for hook in KINDS:
        doc = textwrap.dedent(getattr(hookspecs, hook).__doc__)
        assert "Returns" in doc and "Called once" in doc


def test_the_registry_knows_its_components_parameters_and_parameters_look_nothing_up():
    from fakeplugins import good

    from softcell.model.parameters import Parameters

    with pytest.raises(ConfigError, match="unknown parameter 'fake_level'"):
        default_registry().parameters({"fake_level": 2.0})
    with registered(good) as registry:
        assert registry.parameters({"fake_level": 2.0}).fake_level == 2.0
        with pytest.raises(ConfigError, match=r"'fake_levl' \(did you mean 'fake_level'\?\)"):
            registry.parameters({"fake_levl": 2.0})
        with pytest.raises(ConfigError, match="unknown parameter 'fake_level'"):
            Parameters({"fake_level": 2.0})  # a value object: it never reaches for a registry


def test_a_plugin_both_installed_and_registered_in_a_test_counts_once(tmp_path, monkeypatch):
    import warnings

    import fakeplugins.good

    fake_entry_points(tmp_path, monkeypatch, good="good")
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no 'skipped' warning, no duplicate
        with registered(fakeplugins.good) as registry:
            assert registry.names("stopgo_detector") == ["fake_hysteresis", "threshold"]
            assert registry.skipped == []
