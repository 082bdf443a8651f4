"""The paper's models as presets of the engine (full: dynamic bending; reduced: quasi-static) and
the registry of models by name."""
