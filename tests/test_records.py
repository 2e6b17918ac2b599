"""Recorded accelerograms (dda.io.records): PEER NGA .AT2 and K-NET / KiK-net ASCII files read
exactly, errors that name the file and the line, baseline correction, and the scene format's
[[shake]] file = ... with scale, direction, vertical and baseline."""

import json
import warnings

import numpy as np
import pytest

from dda.effects import AccelerationHistory
from dda.io.records import (
    G,
    RecordError,
    baseline_correct,
    guess_format,
    integrate,
    on_common_times,
    read_at2,
    read_knet,
    read_record,
    write_at2,
)
from dda.io.scene_data import ArrayStore, scene_from_data, scene_to_data
from dda.io.scene_file import SceneFileError, load_scene
from dda.plausibility import PlausibilityWarning
from tests.test_scene_file import FULL, write

# PEER NGA-West2: Fortran E format, five a line, a "stuck" negative on the last line
AT2_WEST2 = """PEER NGA STRONG MOTION DATABASE RECORD
Imperial Valley-02, 5/19/1940, El Centro Array #9, 180
ACCELERATION TIME SERIES IN UNITS OF G
NPTS=     7, DT=   .0050 SEC
  .1234000E-02 -.5000000E-03  .0000000E+00  .2500000E-01 -.1000000E+00
 1.0000000E-01-2.5000000E-02
"""
VALUES = np.array([1.234e-3, -5e-4, 0.0, 2.5e-2, -0.1, 0.1, -2.5e-2])

# the older NGA header: numbers first
AT2_OLD = """PEER NGA STRONG MOTION DATABASE RECORD
IMPERIAL VALLEY 05/19/40 0439, EL CENTRO ARRAY #9, 180
ACCELERATION TIME HISTORY IN UNITS OF G
    7    .00500    NPTS, DT
   .001234   -.000500    .000000    .025000   -.100000    .100000   -.025000
"""

KNET_HEADER = """Origin Time       2011/03/11 14:46:00
Lat.              38.103
Long.             142.860
Depth. (km)       24
Mag.              9.0
Station Code      MYG004
Station Lat.      38.7292
Station Long.     141.0217
Station Height(m) 230
Record Time       2011/03/11 14:46:35
Sampling Freq(Hz) {freq}Hz
Duration Time(s)  300
Dir.              {direction}
Scale Factor      {scale}
Max. Acc. (gal)   {peak}
Last Correction   2011/03/11 14:46:29
Memo.
"""
COUNTS = np.array([6699, 6650, 6612, 6597, 6572, 6535, 6525, 6542, 6580, 6611, 7000, 6100])


def knet_header(counts, freq=100, direction="N-S", scale="3920(gal)/6182761"):
    """The header of a K-NET file of ``counts``, its Max. Acc. theirs (to 3 decimals, as
    NIED writes it)."""
    try:
        num, den = (float(x) for x in scale.replace("(gal)", "").split("/"))
        gal = np.asarray(counts) * num / den
        peak = f"{float(np.abs(gal - gal.mean()).max()):.3f}"
    except (ValueError, ZeroDivisionError):  # a scale factor a test makes wrong on purpose
        peak = "2700.044"
    return KNET_HEADER.format(freq=freq, direction=direction, scale=scale, peak=peak)


def knet_text(counts=COUNTS, freq=100, direction="N-S", scale="3920(gal)/6182761"):
    rows = [" ".join(f"{c:8d}" for c in counts[k:k + 8]) for k in range(0, len(counts), 8)]
    return knet_header(counts, freq, direction, scale) + "\n".join(rows)


def put(tmp_path, name, text):
    f = tmp_path / name
    f.write_text(text)
    return f


# ---------------------------------------------------------------------- PEER .AT2
@pytest.mark.parametrize("text", [AT2_WEST2, AT2_OLD], ids=["west2", "old"])
def test_at2_both_headers_read_exactly(tmp_path, text):
    rec = read_at2(put(tmp_path, "ELC180.AT2", text))
    assert rec.dt == 0.005 and rec.format == "at2" and rec.units == "m/s^2"
    np.testing.assert_array_equal(rec.times, np.arange(7) * 0.005)
    np.testing.assert_array_equal(rec.acceleration, VALUES * 9.80665)
    assert rec.scale_factor == G == 9.80665
    assert rec.direction == "180" and rec.station.upper() == "EL CENTRO ARRAY #9"
    assert rec.baseline == "none" and rec.header["npts"] == "7"


def test_at2_written_and_read_back_in_both_styles(tmp_path):
    a = np.sin(np.linspace(0, 7, 23)) * 0.3
    for style in ("west2", "old"):
        write_at2(tmp_path / f"{style}.AT2", a, dt=0.02, style=style)
        rec = read_record(tmp_path / f"{style}.AT2")
        np.testing.assert_allclose(rec.acceleration, a * G, rtol=1e-7, atol=1e-12)
        assert rec.dt == 0.02 and len(rec.times) == 23


@pytest.mark.parametrize("change, line, words", [
    ("NPTS=     7", "NPTS=     8", "line 4: NPTS = 8 but the file holds 7 values"),
    ("NPTS=     7, DT=   .0050 SEC", "NPTS=     7, DT=   -.005 SEC", "line 4: DT must be"),
    ("NPTS=     7, DT=   .0050 SEC", "7 points at 0.005 s", "line 4: expected 'NPTS="),
    ("ACCELERATION TIME SERIES IN UNITS OF G", "VELOCITY TIME SERIES IN UNITS OF CM/S",
     "line 3: expected 'ACCELERATION"),
    ("ACCELERATION TIME SERIES IN UNITS OF G", "ACCELERATION TIME SERIES IN UNITS OF CM/S/S",
     "line 3: expected acceleration in units of G"),
    (" 1.0000000E-01-2.5000000E-02", " 1.0000000E-01 oops", "line 6: not a number"),
])
def test_at2_that_is_not_what_it_claims_names_file_and_line(tmp_path, change, line, words):
    text = AT2_WEST2.replace(change, line)
    assert text != AT2_WEST2
    with pytest.raises(RecordError) as info:
        read_at2(put(tmp_path, "bad.AT2", text))
    assert str(info.value).startswith("bad.AT2, line ") and words in str(info.value), info.value


# ---------------------------------------------------------------------- K-NET / KiK-net
def test_knet_counts_scale_factor_and_mean(tmp_path):
    rec = read_knet(put(tmp_path, "MYG0041103111446.NS", knet_text()))
    gal = COUNTS * 3920.0 / 6182761.0
    np.testing.assert_allclose(rec.acceleration, (gal - gal.mean()) / 100.0, rtol=0,
                               atol=1e-15)
    assert abs(rec.acceleration.mean()) < 1e-16  # NIED: the record's mean removed
    np.testing.assert_array_equal(rec.times, np.arange(12) / 100.0)
    assert rec.dt == 0.01 and rec.station == "MYG004" and rec.direction == "N-S"
    assert rec.scale_factor == 3920.0 / 6182761.0 / 100.0 and rec.format == "knet"
    # an offset in the counts (the instrument's) is what the mean takes away
    shifted = read_knet(put(tmp_path, "shifted.NS", knet_text(COUNTS + 5000)))
    np.testing.assert_allclose(shifted.acceleration, rec.acceleration, atol=1e-13)


def test_knet_max_acc_against_the_counts(tmp_path):
    """A scale factor pasted from another file scales the whole record; the header's Max.
    Acc. shows it (an earthquake engineer's review: 5000 gal stated over 393 gal read
    without a word). Within 1% (and the header's 3 decimals) nothing is said."""
    text = knet_text()
    stated = text.splitlines()[14]
    with warnings.catch_warnings():
        warnings.simplefilter("error", PlausibilityWarning)
        read_knet(put(tmp_path, "ok.NS", text))
        read_knet(put(tmp_path, "blank.NS", text.replace(stated, "Max. Acc. (gal)")))
    wrong = text.replace(stated, "Max. Acc. (gal)   5000.000")
    with pytest.warns(PlausibilityWarning, match=r"wrong.NS, line 15: Max. Acc. 5000 gal, but "
                      r"the counts .* peak at 0.3\d+ gal .*Scale Factor the file's own"):
        read_knet(put(tmp_path, "wrong.NS", wrong))


def test_kiknet_suffixes_and_200_hz(tmp_path):
    f = put(tmp_path, "IWTH250803140843.EW2", knet_text(freq=200, direction="5",
                                                         scale="7845(gal)/8223790"))
    assert guess_format(f) == "knet"
    rec = read_record(f)
    assert rec.dt == 0.005 and rec.direction == "5"
    assert rec.acceleration.max() == pytest.approx(
        (COUNTS - COUNTS.mean()).max() * 7845 / 8223790 / 100, rel=1e-12)
    assert [guess_format(f"x.{s}") for s in ("at2", "ew", "NS1", "UD2", "csv", "txt")] == [
        "at2", "knet", "knet", "knet", "csv", None]


@pytest.mark.parametrize("change, line, words", [
    ({"scale": "3920(gal)/0"}, 14, "Scale Factor must read like '3920(gal)/6182761'"),
    ({"scale": "3920/6182761"}, 14, "Scale Factor"),
    ({"scale": "3920(cm/s)/6182761"}, 14, "Scale Factor"),
    ({"freq": "fast"}, 11, "Sampling Freq(Hz) must read like '100Hz'"),
])
def test_knet_bad_header_values(tmp_path, change, line, words):
    with pytest.raises(RecordError) as info:
        read_knet(put(tmp_path, "bad.NS", knet_text(**change)))
    assert str(info.value).startswith(f"bad.NS, line {line}: ") and words in str(info.value)


def test_knet_wrong_label_and_bad_value(tmp_path):
    text = knet_text().replace("Dir.    ", "Channel ")
    with pytest.raises(RecordError, match=r"bad.NS, line 13: expected the K-NET header line "
                                          r"'Dir.'"):
        read_knet(put(tmp_path, "bad.NS", text))
    text = knet_text() + "\n    12     x34"
    with pytest.raises(RecordError, match=r"bad.NS, line 20: not a number"):
        read_knet(put(tmp_path, "bad.NS", text))
    with pytest.raises(RecordError, match=r"line 1: expected the K-NET header line"):
        read_knet(put(tmp_path, "x.NS", AT2_WEST2 * 4))
    with pytest.raises(RecordError, match="cannot tell the record's format"):
        read_record(put(tmp_path, "x.txt", AT2_WEST2))
    with pytest.raises(RecordError, match="no record file"):
        read_record(tmp_path / "none.AT2")


# ---------------------------------------------------------------------- baseline
def clean_motion(t):
    """A decaying band-limited motion whose velocity wavers about zero: velocity
    sum_j V_j sin(w_j t) exp(-t / tau), its acceleration analytic."""
    a = np.zeros_like(t)
    for amp, f, tau in ((0.3, 1.3, 2.5), (0.2, 2.9, 1.5), (0.1, 5.3, 1.0)):
        w = 2 * np.pi * f
        e = np.exp(-t / tau)
        a += amp * e * (w * np.cos(w * t) - np.sin(w * t) / tau)
    return a


@pytest.mark.parametrize("method", ["mean", "linear", "quadratic"])
def test_baseline_takes_away_an_offset_and_a_trend_and_ends_at_rest(method):
    t = np.arange(2001) * 0.005            # 10 s at 200 Hz
    a0 = clean_motion(t)
    trend = {"mean": 0.05, "linear": 0.05 + 0.01 * t,
             "quadratic": 0.05 + 0.01 * t + 0.002 * t**2}[method]
    a = a0 + trend
    v_raw = integrate(t, a)[0][-1]
    assert abs(v_raw) > 0.4                 # the trend alone moves the table on at 0.5 m/s
    c = baseline_correct(t, a, method)
    v, u = integrate(t, c)
    # ends at rest: the fit is held to v(T) exactly, so only round-off of the n-term sums is
    # left: n eps sum|a| dt
    assert abs(v[-1]) < len(t) * np.finfo(float).eps * np.abs(a).sum() * 0.005
    # linear in the record and exact on the trends it fits: the record with its trend comes
    # out as the clean record alone does, to round-off of the least squares (cond ~ 1e2)
    np.testing.assert_allclose(c, baseline_correct(t, a0, method), rtol=0, atol=1e-12)
    # a clean record (velocity about zero, peak 9.4 m/s^2) is nearly untouched: the fitted
    # trend is its velocity's slow part (3e-7, 3e-6 and 2.3e-5 of the peak)
    change = np.abs(baseline_correct(t, a0, method) - a0).max()
    assert change < 1e-4 * np.abs(a0).max()
    assert np.abs(baseline_correct(t, a0, "none") - a0).max() == 0.0


def test_baseline_fails_without_the_trend_it_cannot_fit():
    """A lower order cannot take a higher trend away: 'mean' ends at rest but leaves a linear
    trend's displacement (0.83 m here), 'linear' ends where the clean motion does."""
    t = np.arange(2001) * 0.005
    a0 = clean_motion(t)
    a = a0 + 0.01 * t
    u0 = integrate(t, a0)[1][-1]
    _, u_mean = integrate(t, baseline_correct(t, a, "mean"))
    _, u_lin = integrate(t, baseline_correct(t, a, "linear"))
    assert abs(u_mean[-1] - u0) > 0.8 and abs(u_lin[-1] - u0) < 1e-3
    with pytest.raises(ValueError, match="baseline must be"):
        baseline_correct(t, a, "cubic")


def test_the_record_integrals_are_the_shake_history_s():
    t = np.arange(301) * 0.01
    a = clean_motion(t) + 0.02
    v, u = integrate(t, a)
    hist = AccelerationHistory(a, t)
    for k in (17, 150, 300):
        uk, vk = hist.state(t[k])
        assert uk[0] == pytest.approx(u[k], rel=1e-12) and vk[0] == pytest.approx(v[k],
                                                                                  rel=1e-12)


def test_record_corrected_and_end_motion(tmp_path):
    t = np.arange(2001) * 0.005
    write_at2(tmp_path / "drift.AT2", (clean_motion(t) + 0.05) / G, dt=0.005)
    raw = read_at2(tmp_path / "drift.AT2")
    assert raw.end_motion()[0] == pytest.approx(0.5, abs=1e-4)  # 0.05 m/s^2 for 10 s
    fixed = read_at2(tmp_path / "drift.AT2", baseline="mean")
    assert fixed.baseline == "mean" and abs(fixed.end_motion()[0]) < 1e-12
    np.testing.assert_allclose(raw.corrected("mean").acceleration, fixed.acceleration)
    np.testing.assert_array_equal(raw.along((0.0, 2.0))[:, 1], 2 * raw.acceleration)


def test_on_common_times_is_exact_for_piecewise_linear_records():
    ta, tb = np.arange(11) * 0.01, np.arange(7) * 0.015
    va, vb = np.sin(ta * 50), np.cos(tb * 40)
    t, a, b = on_common_times(ta, va, tb, vb)
    assert t[-1] == pytest.approx(0.09) and set(np.round(ta[:10], 12)) <= set(np.round(t, 12))
    np.testing.assert_allclose(a, np.interp(t, ta, va))
    np.testing.assert_allclose(b[np.isin(np.round(t, 12), np.round(tb, 12))], vb[:7])


def test_on_common_times_takes_times_a_bit_apart_as_one():
    """A 200 Hz record and a 100 Hz one: 0.005 k and k / 100 differ in the last bit at
    every other shared instant; the union's 5.6e-17 s spacings were kept as samples (and the
    automatic dt then probed the shaking at that spacing: a MemoryError of 1.88 EiB)."""
    ta, tb = np.arange(2001) * 0.005, np.arange(1001) / 100.0
    assert np.diff(np.union1d(ta, tb)).min() < 1e-15  # the records as they come
    va, vb = np.sin(ta * 7.0), np.cos(tb * 5.0)
    t, a, b = on_common_times(ta, va, tb, vb)
    np.testing.assert_array_equal(t, ta)  # every 100 Hz time is a 200 Hz one
    np.testing.assert_allclose(b[::2], vb, rtol=0, atol=1e-12)
    np.testing.assert_array_equal(a, va)
    # a record's own jump, two samples a hair apart, is kept, first record or second (the
    # second's was a 10 ms ramp where the first also samples the jump's time)
    tj, vj = np.array([0.0, 1.0, 1.0 + 1e-12, 5.0]), np.array([0.0, 0.0, 2.0, 2.0])
    t, a, _ = on_common_times(tj, vj, ta, va)
    assert 1.0 in t and 1.0 + 1e-12 in t
    t, _, b = on_common_times(ta, va, tj, vj)
    np.testing.assert_array_equal(b[np.isin(t, tj)], vj)
    # one sample of the first in the time both cover (an IndexError)
    t, a, b = on_common_times([0.0, 1.0, 2.0], [0.0, 1.0, 2.0], [0.0, 0.5], [1.0, 3.0])
    np.testing.assert_array_equal(t, [0.0, 0.5])
    np.testing.assert_array_equal(a, [0.0, 0.5])


# ---------------------------------------------------------------------- scene files
SHAKE = 'sine = { amplitude = 2.0, frequency = 2.0, start = 0.01 }'


def scene_with(tmp_path, shake_keys, name="scene.toml"):
    return load_scene(write(tmp_path, FULL.replace(SHAKE, shake_keys), name))


def recorded(loaded):
    t, a = loaded.scene.shakes[0].history.record
    return t, a


def test_scene_file_reads_an_at2_record_along_a_direction_scaled(tmp_path):
    put(tmp_path, "ELC180.AT2", AT2_WEST2)
    t, a = recorded(scene_with(tmp_path, 'file = "ELC180.AT2"'))
    np.testing.assert_array_equal(t, np.arange(7) * 0.005)
    np.testing.assert_array_equal(a, np.stack([VALUES * G, 0 * VALUES], axis=1))
    t, a = recorded(scene_with(tmp_path, 'file = "ELC180.AT2"\nscale = 2.0\n'
                                         'direction = [0.6, 0.8]'))
    np.testing.assert_allclose(a, 2.0 * VALUES[:, None] * G * [0.6, 0.8], rtol=1e-15)
    put(tmp_path, "record.txt", AT2_OLD)
    t, a = recorded(scene_with(tmp_path, 'file = "record.txt"\nformat = "at2"'))
    np.testing.assert_allclose(a[:, 0], VALUES * G, rtol=1e-15)


def test_scene_file_knet_horizontal_with_a_vertical_record(tmp_path):
    put(tmp_path, "MYG004.EW", knet_text(direction="E-W"))
    counts_ud = COUNTS[:9] - 6600
    put(tmp_path, "MYG004.UD", knet_text(counts_ud, freq=50, direction="U-D"))
    # the horizontal record ends first: the scene file says so, naming its line (a run past
    # the end was refused naming only the shaken block)
    with pytest.warns(PlausibilityWarning, match=r"scene.toml, line \d+, shake\[0\].file: "
                      r"MYG004.EW ends at t = 0.11 s, 0.05 s before MYG004.UD: the shaking "
                      r"covers the 0.11 s both records cover"):
        loaded = scene_with(tmp_path, 'file = "MYG004.EW"\nvertical = "MYG004.UD"\n'
                                      'scale = 0.5\nbaseline = "mean"')
    t, a = recorded(loaded)
    # records that end a sample of the coarser one apart cover the same time: nothing said
    put(tmp_path, "SHORT.UD", knet_text(counts_ud[:6], freq=50, direction="U-D"))
    with warnings.catch_warnings(record=True) as got:
        warnings.simplefilter("always")
        scene_with(tmp_path, 'file = "MYG004.EW"\nvertical = "SHORT.UD"', "short.toml")
    assert not [w for w in got if "ends at" in str(w.message)]
    ew = read_knet(tmp_path / "MYG004.EW", baseline="mean")
    ud = read_knet(tmp_path / "MYG004.UD", baseline="mean")
    # 100 Hz and 50 Hz: the union of their samples over the time both cover (0.11 s)
    assert t[-1] == pytest.approx(0.11) and len(t) == 12
    np.testing.assert_allclose(a[:, 0], 0.5 * ew.acceleration, atol=1e-15)
    np.testing.assert_allclose(a[::2, 1], 0.5 * ud.acceleration[:6], atol=1e-15)
    np.testing.assert_allclose(a[1::2, 1], 0.25 * (ud.acceleration[:6] + ud.acceleration[1:7]),
                               atol=1e-15)


def test_scene_file_single_column_csv_goes_along_the_direction(tmp_path):
    put(tmp_path, "acc.csv", "t,a\n0,0\n1,1\n2,0\n")
    t, a = recorded(scene_with(tmp_path, 'file = "acc.csv"\ndirection = [0, 1]\nscale = 3'))
    np.testing.assert_array_equal(a, [[0, 0], [0, 3], [0, 0]])
    put(tmp_path, "acc2.csv", "t,ax,ay\n0,0,0\n1,1,2\n2,0,0\n")
    t, a = recorded(scene_with(tmp_path, 'file = "acc2.csv"\nbaseline = "mean"'))
    v, _ = integrate(t, a)
    np.testing.assert_allclose(v[-1], [0.0, 0.0], atol=1e-15)


@pytest.mark.parametrize("keys, key, words", [
    ('file = "rec.dat"', "shake[0].file", "cannot tell the format of 'rec.dat'"),
    ('file = "ELC180.AT2"\nformat = "peer"', "shake[0].format", 'must be "at2"'),
    ('file = "ELC180.AT2"\nbaseline = "cubic"', "shake[0].baseline", "must be 'none'"),
    ('file = "ELC180.AT2"\nscale = 0', "shake[0].scale", "must not be zero"),
    ('file = "ELC180.AT2"\ndirection = [0, 0]', "shake[0].direction", "must not be [0, 0]"),
    ('file = "bad.AT2"', "shake[0].file", "bad.AT2, line 4: NPTS = 8 but the file holds 7"),
    ('file = "acc2.csv"\ndirection = [1, 0]', "shake[0].direction", "two components"),
    (SHAKE + '\nscale = 2.0', "shake[0].scale", "goes with file"),
    ('file = "ELC180.AT2"\nvertical = "acc2.csv"', "shake[0].vertical", "two components"),
])
def test_scene_file_record_errors_name_the_line(tmp_path, keys, key, words):
    put(tmp_path, "ELC180.AT2", AT2_WEST2)
    put(tmp_path, "bad.AT2", AT2_WEST2.replace("NPTS=     7", "NPTS=     8"))
    put(tmp_path, "rec.dat", AT2_WEST2)
    put(tmp_path, "acc2.csv", "t,ax,ay\n0,0,0\n1,1,2\n2,0,0\n")
    with pytest.raises(SceneFileError) as info:
        scene_with(tmp_path, keys)
    msg = str(info.value)
    assert msg.startswith("scene.toml, line ") and f", {key}: " in msg and words in msg, msg
    line = int(msg.split(", line ")[1].split(",")[0])
    shown = (tmp_path / "scene.toml").read_text().splitlines()[line - 1]
    assert key.split(".")[-1] in shown, (msg, shown)


def test_a_scene_with_a_record_file_checkpoints_its_samples(tmp_path):
    put(tmp_path, "ELC180.AT2", AT2_WEST2)
    put(tmp_path, "MYG004.UD", knet_text(direction="U-D"))
    loaded = scene_with(tmp_path, 'file = "ELC180.AT2"\nvertical = "MYG004.UD"')
    store = ArrayStore()
    data = json.loads(json.dumps(scene_to_data(loaded.scene, store)))
    (tmp_path / "ELC180.AT2").unlink()  # the checkpoint needs no file: it holds the samples
    back = scene_from_data(data, ArrayStore(store.arrays))
    for x, y in zip(loaded.scene.shakes[0].history.record, back.shakes[0].history.record,
                    strict=True):
        np.testing.assert_array_equal(x, y)
    sim = loaded.simulation()
    sim.run(0.005, checkpoint=tmp_path / "run.ckpt", progress=False)
    import dda

    assert dda.Simulation.resume(tmp_path / "run.ckpt").state.time == pytest.approx(0.005)
