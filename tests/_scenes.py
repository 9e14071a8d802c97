"""Scenes shared by several test modules (one definition, imported where needed)."""

#: a Duffing oscillator swept over two forcing amplitudes: the small campaign of the cluster
#: tests (local and secured)
DUFFING_SWEEP = {
    "model": {"name": "duffing"},
    "parameters": {"delta": 0.3, "alpha": -1.0, "beta": 1.0, "omega": 1.2},
    "run": {"cycles": 5, "transient_cycles": 5},
    "record": {"samples_per_period": 1},
    "sweep": {"gamma": [0.3, 0.4]},
}
