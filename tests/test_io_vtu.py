"""VTU/PVD output read back with meshio and pyvista equals the Result."""

import xml.etree.ElementTree as ET

import meshio
import numpy as np
import pytest

import dda
from dda.contact import CoulombSingle, JointMaterial
from dda.io.vtu import block_names, field_name
from tests.conftest import box


@pytest.fixture
def run_with_output(tmp_path, rock):
    scene = dda.Scene(gravity=9.81)
    base = scene.add_block(box(0, 0, 1, 0.2), rock, fixed=True, name="base")
    top = scene.add_block(box(0.4, 0.2, 0.2, 0.2), rock, name="top")
    tri = scene.add_block([(0.1, 0.2), (0.3, 0.2), (0.2, 0.35)], rock, name="tri")
    scene.set_joint(JointMaterial(normal_penalty=2e9, shear_penalty=2e9,
                                  friction=CoulombSingle(phi=30)))
    scene.shake(base, acceleration=lambda t: (3.0 * np.sin(2 * np.pi * 5 * t), 0.0))
    writer = dda.io.VTUWriter(tmp_path / "out" / "case")
    result = dda.Simulation(scene, dt=1e-3, record_every=20).run(duration=0.2, output=writer)
    return result, writer, (base, top, tri)


def test_pvd_lists_every_file(run_with_output):
    result, writer, _ = run_with_output
    root = ET.parse(writer.pvd_path).getroot()
    entries = root.findall("./Collection/DataSet")
    assert len(entries) == len(result.time) == len(writer.files) == 11
    np.testing.assert_allclose([float(e.get("timestep")) for e in entries], result.time)
    for e, f in zip(entries, writer.files, strict=True):
        assert f.exists() and f.name == e.get("file")


def test_a_series_written_every_few_frames_ends_at_the_runs_end(tmp_path, rock):
    """VTUWriter(every=3) over 10 recorded steps writes frames 0, 3, 6, 9 and the last one
    (t = 0.01 s): a series that stopped at 0.009 s showed a slope 17 ms before its end."""
    scene = dda.Scene(gravity=9.81)
    scene.add_block(box(0, 0, 1, 0.2), rock, fixed=True, name="base")
    scene.add_block(box(0.4, 0.2, 0.2, 0.2), rock, name="top")
    scene.set_joint(JointMaterial(normal_penalty=2e9, shear_penalty=2e9,
                                  friction=CoulombSingle(phi=30)))
    writer = dda.io.VTUWriter(tmp_path / "case", every=3)
    dda.Simulation(scene, dt=1e-3).run(duration=0.01, output=writer)
    times = [float(e.get("timestep")) for e in
             ET.parse(writer.pvd_path).getroot().findall("./Collection/DataSet")]
    np.testing.assert_allclose(times, [0.0, 0.003, 0.006, 0.009, 0.01], atol=1e-12)
    assert len(writer.files) == 5


def test_a_run_into_an_earlier_runs_folder_leaves_one_series(tmp_path, rock):
    """A 0.02 s run, then a 0.005 s one with the same prefix: the folder holds the second
    run's 6 frames, not those and 15 more of the first (a *.vtu glob, or ParaView's grouped
    series, mixed the two); a half-written file of a killed run goes too, and another
    prefix's files stay."""
    scene = _two_blocks(rock)
    dda.Simulation(scene, dt=1e-3).run(0.02, output=dda.io.VTUWriter(tmp_path / "case"))
    assert len(list(tmp_path.glob("case_*.vtu"))) == 21
    (tmp_path / "case_00021.vtu.part").write_bytes(b"")  # a killed run's last file
    (tmp_path / "case_00022.vtu.tmp.vtu").write_bytes(b"")  # (the name it had before)
    (tmp_path / "case_x_00001.vtu").write_bytes(b"other")  # another prefix: "case_x"
    (tmp_path / "case_notes.vtu").write_bytes(b"mine")
    writer = dda.io.VTUWriter(tmp_path / "case")
    dda.Simulation(_two_blocks(rock), dt=1e-3).run(0.005, output=writer)
    series = sorted(p.name for p in tmp_path.glob("case_*"))
    assert series == sorted([f.name for f in writer.files] + ["case_x_00001.vtu",
                                                              "case_notes.vtu"])
    assert len(writer.files) == 6


def test_a_writer_takes_one_series(tmp_path, rock):
    """One writer handed to a second simulation from t = 0 wrote times going back in one
    .pvd; it is refused, and a run that goes on from where the writer stands is not; a
    non-whole every (1.5, taken as 1) is refused."""
    writer = dda.io.VTUWriter(tmp_path / "case")
    sim = dda.Simulation(_two_blocks(rock), dt=1e-3)
    sim.run(0.005, output=writer)
    sim.run(0.005, output=writer)  # goes on from 0.005 s
    with pytest.raises(ValueError, match=r"already reaches t = 0.01 s and this run starts at "
                                         r"t = 0 s"):
        dda.Simulation(_two_blocks(rock), dt=1e-3).run(0.005, output=writer)
    times = [float(e.get("timestep")) for e in
             ET.parse(writer.pvd_path).getroot().findall("./Collection/DataSet")]
    assert np.all(np.diff(times) > 0) and len(times) == 11
    for every in (1.5, 0, True):
        with pytest.raises(ValueError, match="every must be a whole number"):
            dda.io.VTUWriter(tmp_path / "x", every=every)


def _two_blocks(rock):
    scene = dda.Scene(gravity=9.81)
    scene.add_block(box(0, 0, 1, 0.2), rock, fixed=True, name="base")
    scene.add_block(box(0.4, 0.2, 0.2, 0.2), rock, name="top")
    scene.set_joint(JointMaterial(normal_penalty=2e9, shear_penalty=2e9,
                                  friction=CoulombSingle(phi=30)))
    return scene


def test_a_series_written_at_an_interval_of_simulated_time(tmp_path, rock):
    """VTUWriter(interval=1e-3) over steps of 4e-4 s writes the first step at least 1 ms
    after the last written (0, 1.2, 2.4, ... ms) and the run's end; over frames whose
    spacing changes (cut steps) it keeps its frames at least the interval apart."""
    from dataclasses import replace

    writer = dda.io.VTUWriter(tmp_path / "case", interval=1e-3)
    sim = dda.Simulation(_two_blocks(rock), dt=4e-4)
    sim.run(duration=0.01, output=writer)
    times = [float(e.get("timestep")) for e in
             ET.parse(writer.pvd_path).getroot().findall("./Collection/DataSet")]
    np.testing.assert_allclose(times, [0.0, 0.0012, 0.0024, 0.0036, 0.0048, 0.006, 0.0072,
                                       0.0084, 0.0096, 0.01], atol=1e-12)
    frame = sim.frame()
    steps = [0.0, 0.002, 0.0025, 0.003, 0.0031, 0.0032, 0.0045, 0.005, 0.0051, 0.0062]
    uneven = dda.io.VTUWriter(tmp_path / "uneven", interval=2e-3)
    for i, t in enumerate(steps):
        uneven.write(replace(frame, time=t), last=i == len(steps) - 1)
    assert [t for t, _ in uneven._entries] == [0.0, 0.002, 0.0045, 0.0062]


class _EveryFrame:
    """A writer that takes every frame and hands it on (a writer without ``due``)."""

    def __init__(self, inner):
        self.inner, self.every, self.interval = inner, inner.every, inner.interval

    def write(self, frame, last=False):
        self.inner.write(frame, last=last)

    def close(self):
        self.inner.close()


@pytest.mark.parametrize("kwargs", [{"interval": 1e-3}, {"every": 4}])
def test_a_thinned_series_builds_only_the_frames_it_writes(tmp_path, rock, monkeypatch, kwargs):
    """The recorder asks the writer whether a frame is due before it builds it: over 25
    steps a writer thinned to every 1.2 ms (or every 4th step) costs 10 (or 8) frames, not 26,
    and writes the same files as when it is handed every frame."""
    import dda.recorder as recorder

    built = []
    build = recorder.frame
    monkeypatch.setattr(recorder, "frame", lambda *a: built.append(1) or build(*a))
    thinned = dda.io.VTUWriter(tmp_path / "thinned" / "case", **kwargs)
    dda.Simulation(_two_blocks(rock), dt=4e-4).run(duration=0.01, output=thinned)
    assert len(built) == len(thinned.files) == (10 if "interval" in kwargs else 8)
    built.clear()
    handed = dda.io.VTUWriter(tmp_path / "handed" / "case", **kwargs)
    dda.Simulation(_two_blocks(rock), dt=4e-4).run(duration=0.01, output=_EveryFrame(handed))
    assert len(built) == 26
    assert [e[0] for e in handed._entries] == [e[0] for e in thinned._entries]
    for a, b in zip(handed.files, thinned.files, strict=True):
        assert a.name == b.name and a.read_bytes() == b.read_bytes()


@pytest.mark.parametrize("kwargs", [{"interval": 0.0}, {"interval": -1.0},
                                    {"interval": float("nan")}, {"interval": 1e-3, "every": 2}])
def test_an_interval_must_be_a_positive_time_and_alone(tmp_path, kwargs):
    with pytest.raises(ValueError, match="VTUWriter"):
        dda.io.VTUWriter(tmp_path / "case", **kwargs)


def _block_rows(mesh, name):
    ids = np.concatenate(mesh.cell_data["block_id"])
    vals = np.concatenate(mesh.cell_data[name])
    keep = ids >= 0
    return ids[keep].astype(int), vals[keep]


def test_meshio_fields_equal_the_result(run_with_output):
    result, writer, blocks = run_with_output
    for i, path in enumerate(writer.files):
        mesh = meshio.read(path)
        for field, getter, ncomp in (("displacement", result.displacement, 2),
                                     ("stress", result.stress, 3)):
            ids, vals = _block_rows(mesh, field)
            for b in blocks:
                row = vals[ids == b.index][0][:ncomp]
                np.testing.assert_allclose(row, getter(b)[i], rtol=1e-12, atol=1e-15)
        ids, vel = _block_rows(mesh, "velocity")
        for b in blocks:
            np.testing.assert_allclose(vel[ids == b.index][0][:2], result.velocity(b)[i, :2],
                                       rtol=1e-12, atol=1e-15)
        # contacts: the normal forces on the top block add up to the joint force
        kind = np.concatenate(mesh.cell_data["kind"])
        fn = np.concatenate(mesh.cell_data["normal_force"])[kind == 1]
        assert np.all(fn >= 0)


def test_pyvista_reads_the_series(run_with_output):
    pv = pytest.importorskip("pyvista")
    result, writer, (base, top, tri) = run_with_output
    reader = pv.get_reader(str(writer.pvd_path))
    assert len(reader.time_values) == len(result.time)
    reader.set_active_time_point(len(result.time) - 1)
    grid = reader.read()[0]
    ids = grid.cell_data["block_id"]
    row = np.flatnonzero(ids == top.index)[0]
    # (a component near zero, -2.3e-7 m, differs from the Result's in its last bits)
    np.testing.assert_allclose(grid.cell_data["displacement"][row][:2],
                               result.displacement(top)[-1], rtol=1e-12, atol=1e-15)
    # vertex displacements: the point data of the top block's corners
    first = 4 * top.index
    moved = grid.points[first:first + 4, :2] - np.array(box(0.4, 0.2, 0.2, 0.2))
    np.testing.assert_allclose(grid.point_data["displacement"][first:first + 4, :2], moved,
                               atol=1e-12)
    contact_cells = np.flatnonzero(grid.cell_data["kind"] == 1)
    total = grid.cell_data["normal_force"][contact_cells].sum()
    joint = sum(result.joint_force(a, b)[-1, 0] for a, b in ((base, top), (base, tri)))
    assert total == pytest.approx(joint, rel=1e-3)


def test_compiled_pair_forces_are_the_numpy_ones():
    """The recorder's per-pair force sums come from a compiled kernel: the numpy version's
    keys and numbers to the bit, on the many contacts of a shaken jointed slope."""
    from dda.contact.contacts import OPEN, pair_key
    from dda.contact.detection import _groups
    from dda.recorder import pair_forces
    from tests.stability import scenes

    sim = dda.Simulation(scenes.shaken_cut_slope()[0], dt=2e-3)
    sim.run(0.02, progress=False)
    model, state = sim.model, sim.state
    c = state.contacts
    closed = (c.state != OPEN).nonzero()[0]
    edge = c.edge[closed]
    d = state.x[edge] - state.x[model.topo.nxt[edge]]
    tau = d / np.hypot(d[:, 0], d[:, 1])[:, None]
    g_normal = np.stack([-tau[:, 1], tau[:, 0]], axis=1)
    bj, bk = c.bj[closed], c.bk[closed]
    t_n, t_s = c.t_n[closed], c.t_s[closed]
    sign = np.where(bj > bk, 1.0, -1.0)[:, None]
    keys, _, inv = _groups(pair_key(bj, bk, model.n_blocks))
    f, n = np.zeros((len(keys), 2)), np.zeros((len(keys), 2))
    np.add.at(f, inv, sign * -(t_n[:, None] * g_normal + t_s[:, None] * tau))
    np.add.at(n, inv, sign * g_normal * np.abs(t_n)[:, None])
    got = pair_forces(model, state)
    assert len(keys) > 20 and len(closed) > len(keys)
    for have, want in zip(got, (keys, f, n), strict=True):
        np.testing.assert_array_equal(have, want)


def _cells(mesh, name):
    return np.concatenate(mesh.cell_data[name])


def test_field_names_carry_their_units(run_with_output):
    _, writer, _ = run_with_output
    mesh = meshio.read(writer.files[-1])
    for name in ("displacement [m]", "velocity [m/s]", "rotation [rad]", "stress [Pa]",
                 "normal_force [N/m]", "shear_force [N/m]", "normal_force_vector [N/m]",
                 "shear_force_vector [N/m]"):
        assert name in mesh.cell_data
    assert {"displacement [m]", "velocity [m/s]"} <= set(mesh.point_data)
    # the names of before stay, the same numbers
    for plain in ("displacement", "velocity", "rotation", "stress", "normal_force",
                  "shear_force"):
        np.testing.assert_array_equal(_cells(mesh, plain), _cells(mesh, field_name(plain)))
    np.testing.assert_array_equal(mesh.point_data["displacement"],
                                  mesh.point_data["displacement [m]"])


def test_plain_names_can_be_left_out(tmp_path, rock):
    scene = dda.Scene(gravity=9.81)
    scene.add_block(box(0, 0, 1, 0.2), rock, fixed=True, name="base")
    scene.add_block(box(0.4, 0.2, 0.2, 0.2), rock, name="top")
    scene.set_joint(JointMaterial(normal_penalty=2e9, shear_penalty=2e9,
                                  friction=CoulombSingle(phi=30)))
    writer = dda.io.VTUWriter(tmp_path / "case", plain_names=False)
    dda.Simulation(scene, dt=1e-3).run(duration=2e-3, output=writer)
    mesh = meshio.read(writer.files[-1])
    assert "displacement [m]" in mesh.cell_data and "displacement" not in mesh.cell_data
    assert set(mesh.point_data) == {"displacement [m]", "velocity [m/s]"}
    assert block_names(mesh.field_data) == ["base", "top"]


def test_contact_force_vectors(run_with_output):
    """Each contact's vectors are its scalar forces along the edge's normal and tangent, as
    forces on the vertex's block: summed over a pair's contacts they give the Result's joint
    force."""
    result, writer, (base, top, tri) = run_with_output
    for i in (5, len(writer.files) - 1):
        mesh = meshio.read(writer.files[i])
        on = _cells(mesh, "kind") == 1
        fn, fs = _cells(mesh, "normal_force")[on], _cells(mesh, "shear_force")[on]
        vn = _cells(mesh, "normal_force_vector [N/m]")[on]
        vs = _cells(mesh, "shear_force_vector [N/m]")[on]
        assert len(fn) >= 4 and np.all(vn[:, 2] == 0) and np.all(vs[:, 2] == 0)
        np.testing.assert_allclose(np.linalg.norm(vn, axis=1), np.abs(fn), rtol=1e-12)
        np.testing.assert_allclose(np.linalg.norm(vs, axis=1), np.abs(fs), rtol=1e-12,
                                   atol=1e-12 * np.abs(fn).max())
        # the normal direction (unit, out of the edge's block) and the tangent are orthogonal
        n = vn[:, :2] / fn[:, None]
        np.testing.assert_allclose(np.linalg.norm(n, axis=1), 1.0, rtol=1e-12)
        tau = np.stack([n[:, 1], -n[:, 0]], axis=1)
        np.testing.assert_allclose(vs[:, :2], -fs[:, None] * tau, rtol=1e-12, atol=1e-9)
        vertex = _cells(mesh, "vertex_block")[on]
        edge = _cells(mesh, "edge_block")[on]
        for b in (top, tri):
            pair = ((vertex == b.index) & (edge == base.index)) | (
                (vertex == base.index) & (edge == b.index))
            sign = np.where(vertex[pair] == b.index, 1.0, -1.0)[:, None]
            force = (sign * (vn + vs)[pair, :2]).sum(axis=0)  # on b, from the base
            weighted = (sign * vn[pair, :2]).sum(axis=0)
            nbar = weighted / np.linalg.norm(weighted)
            want = result.joint_force(base, b)[i]
            np.testing.assert_allclose([force @ nbar, force @ [nbar[1], -nbar[0]]], want,
                                       rtol=1e-9, atol=1e-9 * abs(want[0]))
            assert force[1] > 0  # the base holds the block up


def test_block_names_ids_and_the_shaken_block_round_trip(run_with_output):
    pv = pytest.importorskip("pyvista")
    _, writer, blocks = run_with_output
    path = writer.files[-1]
    mesh = meshio.read(path)
    grid = pv.read(str(path))
    for names, ids, shaken, kind in (
            (block_names(mesh.field_data), _cells(mesh, "block_id"), _cells(mesh, "shaken"),
             _cells(mesh, "kind")),
            (block_names(grid.field_data), grid.cell_data["block_id"],
             grid.cell_data["shaken"], grid.cell_data["kind"])):
        assert names == ["base", "top", "tri"]
        assert np.issubdtype(np.asarray(ids).dtype, np.integer)
        assert sorted(ids[kind == 0]) == [0, 1, 2] and np.all(ids[kind == 1] == -1)
        assert list(ids[(kind == 0) & (shaken == 1)]) == [blocks[0].index]
    # the cells of a block are that block's polygon
    top = np.flatnonzero(grid.cell_data["block_id"] == blocks[1].index)[0]
    corners = grid.get_cell(top).points[:, :2]
    moved = np.array(box(0.4, 0.2, 0.2, 0.2)) + grid.cell_data["displacement [m]"][top, :2]
    np.testing.assert_allclose(corners.mean(axis=0), moved.mean(axis=0), atol=1e-6)


def test_pyvista_draws_the_force_vectors_as_arrows(run_with_output):
    pv = pytest.importorskip("pyvista")
    _, writer, _ = run_with_output
    grid = pv.read(str(writer.files[-1]))
    contacts = grid.extract_cells(np.flatnonzero(grid.cell_data["kind"] == 1))
    arrows = contacts.glyph(orient="normal_force_vector [N/m]", scale=False, factor=0.05)
    assert arrows.n_points > 0
    # the blocks rest on the base: the forces on them (the vertices' blocks) point up
    low, high = contacts.bounds[2], arrows.bounds[3]
    assert high == pytest.approx(contacts.bounds[3] + 0.05, rel=1e-3)
    assert arrows.bounds[2] >= low - 1e-3


@pytest.mark.parametrize("how", ["interrupt", "cannot go on", "a callback's error"])
def test_a_stopped_thinned_series_ends_where_the_run_stopped(tmp_path, rock, how):
    """A run with VTUWriter(every=5) stopped after its 13th step (Ctrl-C, or a step that
    cannot go on) writes its last committed state as the series' last frame; it ended at
    the 10th before (the reviewer's run: stopped at 8.39632 s, last frame 8.38832 s)."""
    writer = dda.io.VTUWriter(tmp_path / "case", every=5)
    sim = dda.Simulation(_two_blocks(rock), dt=1e-3)

    raised = {"interrupt": KeyboardInterrupt, "cannot go on": dda.SimulationError,
              "a callback's error": ValueError}[how]

    def stop(state, report):
        if state.time > 0.0125:
            raise raised("stopped by the test")

    with pytest.raises(raised):
        sim.run(0.05, output=writer, callback=stop)
    times = [float(e.get("timestep")) for e in
             ET.parse(writer.pvd_path).getroot().findall("./Collection/DataSet")]
    assert sim.committed.time == pytest.approx(0.013)
    np.testing.assert_allclose(times, [0.0, 0.005, 0.010, 0.013], atol=1e-12)


def test_a_run_that_goes_on_after_a_stop_does_not_write_its_frame_again(rock):
    """The stopped state's frame, written at the stop, was written again by the next run of
    the same simulation for a writer without last_time (any write/close object)."""

    class Times:
        def __init__(self):
            self.times = []

        def write(self, frame, last=False):
            self.times.append(frame.time)

        def close(self):
            pass

    writer = Times()
    sim = dda.Simulation(_two_blocks(rock), dt=2e-3, record_every=3)

    def stop(state, report):
        if state.time > 0.021:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        sim.run(0.05, output=writer, callback=stop)
    sim.run(0.01, output=writer)
    assert np.all(np.diff(writer.times) > 0), writer.times
