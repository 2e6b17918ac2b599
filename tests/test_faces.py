"""Faces: which vertex-edge contacts form one face, and the face-onset friction rule."""

import numpy as np
import pytest

import dda
from dda.contact import JointMaterial, StaticDynamicTransition
from dda.contact.faces import Faces, contact_faces
from dda.materials import LinearElastic
from tests.conftest import box, capture_step_problem, wedge_scene
from tests.test_newton import convergence_order

ROCK = LinearElastic(young=1e9, poisson=0.25, density=2500.0)
PUSH = 2.0  # table acceleration, m/s^2, held constant after a smooth ramp


def ramp(t):
    return (PUSH * min(t / 0.1, 1.0) ** 2, 0.0)


def shaken(uppers, duration=0.3):
    """Blocks on a fixed base pushed sideways by the table: stuck, they move with it."""
    scene = dda.Scene(gravity=9.81)
    base = scene.add_block(box(0, 0, 2, 0.2), ROCK, fixed=True, name="base")
    for corners in uppers:
        scene.add_block(corners, ROCK)
    scene.set_joint(JointMaterial(normal_penalty=1e9, shear_penalty=1e9,
                                  friction=StaticDynamicTransition(40.0, 30.0, onset="face")))
    scene.shake(base, acceleration=ramp)
    sim = dda.Simulation(scene, dt=1e-3)
    sim.run(duration)
    return sim


def faces_of(sim):
    c = sim.state.contacts
    closed = c.state != 0
    faces = contact_faces(sim.state.x, c.vertex, c.edge, sim.model.topo.nxt, sim.model.topo.prv)
    return faces.subset(np.flatnonzero(closed)), c.t_s[closed], c.bj[closed]


def test_a_block_on_a_wider_block_is_one_face_and_its_shear_is_the_push():
    sim = shaken([box(0.8, 0.2, 0.3, 0.2)])
    faces, t_s, _ = faces_of(sim)
    assert len(t_s) == 2 and len(np.unique(faces.index)) == 1
    mass = 0.3 * 0.2 * 2500.0
    np.testing.assert_allclose(np.abs(faces.total(t_s)), mass * PUSH, rtol=0.01)


def test_offset_faces_swap_roles_and_their_shear_forces_still_add_up():
    """Over the base's corner: one contact is the block's vertex, the other the base's."""
    sim = shaken([box(1.8, 0.2, 0.3, 0.2)])
    faces, t_s, bj = faces_of(sim)
    assert len(t_s) == 2 and len(set(bj)) == 2  # the roles are swapped
    assert len(np.unique(faces.index)) == 1
    mass = 0.3 * 0.2 * 2500.0
    np.testing.assert_allclose(np.abs(faces.total(t_s)), mass * PUSH, rtol=0.01)
    assert np.all(t_s < 0) and np.all(np.abs(t_s) > 0.2 * mass * PUSH)  # both carry a share


def test_separate_blocks_and_a_corner_make_separate_faces():
    tilted = np.array(box(-0.1, -0.1, 0.2, 0.2))
    c, s = np.cos(np.radians(30)), np.sin(np.radians(30))
    tilted = tilted @ np.array([[c, s], [-s, c]])
    tilted += [1.5, 0.2 - tilted[:, 1].min()]
    sim = shaken([box(0.2, 0.2, 0.3, 0.2), box(0.7, 0.2, 0.3, 0.2), tilted], duration=0.01)
    faces, t_s, bj = faces_of(sim)
    assert len(t_s) == 5
    per_block = {b: set(faces.index[bj == b]) for b in set(bj)}
    assert [len(v) for v in per_block.values()] == [1, 1, 1]
    assert len(np.unique(faces.index)) == 3


def test_face_totals_count_only_the_selected_contacts():
    faces = Faces(np.array([4, 4, 7, 4]))
    np.testing.assert_array_equal(faces.total(np.array([1.0, 2.0, 3.0, 4.0])), [7, 7, 3, 7])
    part = faces.subset(np.array([0, 2]))
    np.testing.assert_array_equal(part.total(np.array([1.0, 3.0])), [1, 3])
    np.testing.assert_array_equal(Faces.separate(3).total(np.ones(3)), np.ones(3))


def onset_case(onset, share):
    """Two contacts of one face, 100 N and 300 N normal force, with trial shear forces
    ``share`` (N); the face is given only to the face rule."""
    law = StaticDynamicTransition(40.0, 30.0, onset=onset)
    t_n = np.array([-100.0, -300.0])
    trial_force = np.asarray(share, dtype=float)
    ps = np.full(2, 1e6)
    faces = Faces(np.array([0, 0])) if onset == "face" else None
    return law, law.return_map(law.initial_state(2), trial_force / ps, t_n, ps, np.ones(2),
                               faces=faces)


def test_face_onset_waits_for_the_face_and_then_drops_both_contacts():
    mu_s, mu_d = np.tan(np.radians(40.0)), np.tan(np.radians(30.0))
    # equal shear, 150 N each: the lightly pressed contact is above its own strength (83.9 N)
    # but the face (300 N) is below its strength (335.6 N)
    _, per_contact = onset_case("contact", [150.0, 150.0])
    np.testing.assert_array_equal(per_contact.slipping, [True, False])
    _, per_face = onset_case("face", [150.0, 150.0])
    np.testing.assert_array_equal(per_face.slipping, [False, False])
    np.testing.assert_allclose(per_face.t_s, [150.0, 150.0])
    # just above the face's strength both contacts drop to the dynamic strength together
    over = 1.001 * mu_s * 400.0 / 2
    _, per_face = onset_case("face", [over, over])
    np.testing.assert_array_equal(per_face.slipping, [True, True])
    np.testing.assert_allclose(per_face.t_s, mu_d * np.array([100.0, 300.0]))


def test_a_sliding_contact_counts_with_its_dynamic_force():
    law = StaticDynamicTransition(40.0, 30.0, onset="face")
    mu_s, mu_d = law.mu_static, law.mu_dynamic
    committed = law.initial_state(2)
    committed["sliding"][0] = 1.0  # the first contact slides, the second has re-stuck
    t_n = np.array([-100.0, -300.0])
    ps = np.full(2, 1.0)
    faces = Faces(np.array([0, 0]))
    for second, slips in [(0.99 * mu_s * 300.0, False), (1.01 * mu_s * 300.0, True)]:
        # the sliding contact's trial is far beyond its strength: it counts as mu_d * 100 only
        trial = law.return_map(committed, np.array([5 * mu_d * 100.0, second]), t_n, ps,
                               np.ones(2), faces=faces)
        assert trial.slipping[0]
        assert trial.slipping[1] == slips


def test_without_faces_the_face_law_judges_each_contact():
    law, trial = onset_case("face", [150.0, 150.0])
    per_contact = law.return_map(law.initial_state(2), np.array([150.0, 150.0]) / 1e6,
                                 np.array([-100.0, -300.0]), np.full(2, 1e6), np.ones(2))
    np.testing.assert_array_equal(per_contact.slipping, [True, False])
    assert not trial.slipping.any()


def test_onset_is_checked():
    with pytest.raises(ValueError, match="onset"):
        StaticDynamicTransition(40.0, 30.0, onset="block")
    assert "onset='contact'" in repr(StaticDynamicTransition(40.0, 30.0, onset="contact"))
    assert "onset" not in repr(StaticDynamicTransition(40.0, 30.0, onset="face"))
    # the rigid block's rule is the default (issue 20); the papers' per-contact one is asked for
    assert StaticDynamicTransition(40.0, 30.0).uses_faces is True
    assert StaticDynamicTransition(40.0, 30.0).onset == "face"
    assert StaticDynamicTransition(40.0, 30.0, onset="contact").uses_faces is False


def test_newton_converges_quadratically_with_face_onset():
    """A block sliding down a free wedge: both contacts of its face slip, at the dynamic angle."""
    law = StaticDynamicTransition(20.0, 15.0, onset="face")
    scene, _, _ = wedge_scene(penalty=1e7, law=law)
    sim = dda.Simulation(scene, dt=1e-3, solver=dda.solvers.NewtonRaphson())
    sim.run(0.05)
    problem = capture_step_problem(sim, 1e-3)
    reference = dda.solvers.NewtonRaphson(tol=1e-14).solve_step(problem)
    assert (reference.contacts.state == 2).sum() == 2  # the block's face; the wedge sticks
    d = reference.d.copy()
    d[problem.free, 2] += 0.01 * np.array([1.0, -1.0])
    sol = dda.solvers.NewtonRaphson(tol=1e-14).iterate(problem, d)
    assert sol.converged
    np.testing.assert_allclose(sol.d, reference.d, rtol=0, atol=1e-12)
    assert convergence_order(sol.residual_norms, floor=1e-7) >= 1.8


def _faces_numpy(x, vertex, edge, nxt, prv, angle=5.0):
    """The grouping in plain numpy (the compiled kernel's reference)."""
    def unit(v):
        return v / np.linalg.norm(v, axis=-1, keepdims=True)

    m = len(vertex)
    tau = unit(x[nxt[edge]] - x[edge])
    own = np.stack([vertex, prv[vertex]], axis=1)
    cos = np.einsum("mkj,mj->mk", unit(x[nxt[own]] - x[own]), tau)
    pick = np.argmin(cos, axis=1)
    opposite = cos[np.arange(m), pick] <= -np.cos(np.radians(angle))
    other = own[np.arange(m), pick]
    n = len(x)
    key = np.where(opposite, np.minimum(edge, other) * n + np.maximum(edge, other),
                   n * n + np.arange(m))
    return np.unique(key, return_inverse=True)[1]


@pytest.mark.parametrize("angle", [5.0, 30.0])
def test_compiled_faces_match_numpy(angle):
    """The compiled grouping numbers the faces as the numpy version does, on the contacts of
    a shaken jointed slope (faces, corners, both roles of a block)."""
    from tests.stability import scenes

    scene, dt = scenes.shaken_cut_slope()[:2]
    sim = dda.Simulation(scene, dt=dt)
    sim.run(0.02, progress=False)
    c, topo = sim.state.contacts, sim.model.topo
    assert len(c) > 50
    got = contact_faces(sim.state.x, c.vertex, c.edge, topo.nxt, topo.prv, angle).index
    want = _faces_numpy(sim.state.x, c.vertex, c.edge, topo.nxt, topo.prv, angle)
    np.testing.assert_array_equal(got, want)
    assert 1 < len(np.unique(got)) < len(c)
