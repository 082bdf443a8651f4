"""What a damping ratio of each panel gives the deployed structure, said in the run's notes,
and a budget message that proposes no damping the scene already has (issue 57)."""

import dataclasses
import re

import numpy as np

from rodval.core.damping import DampingRequest, bending_damping_for_ratio
from rodval.core.scene_file import scene_from_dict
from rodval.models import simulate
from rodval.models.observation.deployed_damping import deployed_scene, first_mode, panel_note

#: A three-panel wing, stiff root spring, latches on hinges 1 and 2, 1 % of each panel.
WING = {
    "n": 3,
    "t_end": 0.01,
    "chain": {
        "l": 1.5,
        "m": 3.0,
        "EI": 5e4,
        "kappa": [1e5, 50.0, 50.0],
        "nu": [10.0, 0.05, 0.05],
        "bending_damping": {"ratio": 0.01},
    },
    "initial": {"phi": [0.0, 3.0915926535897933, 0.0]},
    "latches": [{"hinge": 1, "angle": 0.0}, {"hinge": 2, "angle": 0.0}],
}


def test_the_note_states_the_deployed_structures_ratio():
    """The note's Hz and ratio are the first mode of the deployed structure with the panel
    ratio's c, computed here from the converted c; a run records it in its notes."""
    scene = scene_from_dict(WING)
    c = bending_damping_for_ratio(0.01, 1.5, 3.0, 5e4)
    omega, zeta = first_mode(deployed_scene(scene, np.full(3, c)))
    (note,) = panel_note(scene)
    hz, ratio = re.search(r"\(([0-9.e+-]+) Hz.* a ratio of ([0-9.e+-]+);", note).groups()
    assert float(hz) == float(f"{omega / (2 * np.pi):.3g}")
    assert float(ratio) == float(f"{zeta:.2g}")
    assert 0 < zeta < 0.01  # the structure's slower mode is damped less than each panel
    assert note.startswith("bending_damping ratio 0.01 of each panel's first mode")
    assert 'of = "deployed" states that ratio instead' in note
    assert note in simulate(scene, "rigid").stats.notes


def test_no_note_without_latches_damping_ratio_or_a_first_mode():
    """No note on a scene without latches, without a panel ratio (c in N m^2 s, or none), or
    whose deployed structure is a mechanism (a hinge with neither latch nor spring)."""
    assert panel_note(scene_from_dict({**WING, "latches": []})) == []
    chain = {**WING["chain"], "bending_damping": 2.0}
    assert panel_note(scene_from_dict({**WING, "chain": chain})) == []
    assert panel_note(scene_from_dict({**WING, "chain": {**chain, "bending_damping": 0.0}})) == []
    loose = {**WING["chain"], "kappa": [0.0, 50.0, 50.0]}
    assert panel_note(scene_from_dict({**WING, "chain": loose})) == []


def test_a_budget_message_on_a_damped_scene_gives_its_damping_not_more_of_it():
    """The rigid two-rod latch with EI 1e9 and 1 % of each rod: its budget goes on the rods'
    bending as undamped; the message gives the damping the scene has (c and its ratio) and
    proposes a larger ratio, of = "deployed", the reduced or rigid model, looser tolerances,
    not to damp the bending it damps already."""
    from rodval.bench.stiffness import rigid_latch
    from rodval.core.status import STATUS_BUDGET

    scene = rigid_latch(1e9)
    c = bending_damping_for_ratio(0.01, 1.0, 1.0, 1e9)
    chain = scene.chain.with_(bending_damping=np.full(2, c))
    scene = dataclasses.replace(scene, chain=chain, damping=DampingRequest(0.01))
    stats = simulate(scene, "full", max_evaluations=100_000).stats
    assert stats.status == STATUS_BUDGET
    assert "damp the rods' bending" not in stats.message
    assert f"damped already (c = {c:.3g} N m^2 s, a ratio of 0.01 of each rod" in stats.message
    assert 'a larger ratio, or of = "deployed"' in stats.message
    assert "the reduced model" in stats.message and "a looser rtol and atol" in stats.message
