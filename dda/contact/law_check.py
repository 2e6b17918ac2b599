"""Check any friction law the way the test suite checks the package's own.

:func:`check_friction_law` samples contacts that stick and contacts that slip, fresh and with a
history, and checks what the solvers rely on: the consistent tangent against central finite
differences, a committed history that no trial touches, a slipping force within its trial
and against the slip, a stick spring that pushes back, history of float arrays, results that
do not depend on how many contacts are evaluated together, the stick branch, a law that
survives pickling (parallel sweeps copy it), and one rebuilt from its constructor's
parameters, kept as its attributes, that gives the same forces (checkpoints keep it so).
"""

from __future__ import annotations

import copy
import pickle

import numpy as np

from dda.contact.friction import FrictionLaw, FrictionTrial

__all__ = ["check_friction_law"]

#: the step size (s) a law that asks for one (``FrictionLaw.uses_dt``) is checked at
CHECK_DT = 1e-3


def check_friction_law(law, *, normal_forces=(1e2, 1e6), normal_penalty: float = 1e10,
                       shear_penalty: float = 1e9, contacts: int = 64, rtol: float = 1e-5,
                       seed: int = 0) -> None:
    """Check a friction law instance; raise ``AssertionError`` saying what is wrong.

    Parameters
    ----------
    law : FrictionLaw
        The instance to check, with the parameters it will run with.
    normal_forces : (float, float)
        Range of the compressive normal forces ``|t_n|`` sampled (N per m, log-uniform). The
        shear trials range over ``-3 |t_n| .. 3 |t_n|``, so a law that never slips (or never
        sticks) there should be given forces where it does.
    normal_penalty, shear_penalty : float
        ``p_n`` and ``p_s`` of the sampled contacts (N/m).
    contacts : int
        Number of sampled contacts per history.
    rtol : float
        Relative tolerance of the tangent against finite differences (the absolute part is
        ``1e-6 p``).
    seed : int
        Seed of the sample (the check is deterministic).

    Returns
    -------
    None
        When every check passes.

    Examples
    --------
    >>> from dda.contact import CoulombSingle, check_friction_law
    >>> check_friction_law(CoulombSingle(phi=30.0, cohesion=1e4))
    """
    _assert(isinstance(law, FrictionLaw),
            f"{law!r} is not a dda.contact.FrictionLaw (subclass FrictionLaw or CoulombLike)")
    rng = np.random.default_rng(seed)
    n = int(contacts)
    pn, ps = np.full(n, float(normal_penalty)), np.full(n, float(shear_penalty))
    lo, hi = np.log10(normal_forces[0]), np.log10(normal_forces[1])
    t_n = -(10.0 ** rng.uniform(lo, hi, n))
    length = rng.uniform(0.05, 1.0, n)
    fields = _check_history_fields(law, n)
    fresh = law.initial_state(n)
    # a used history: one step of random shear from the fresh state, committed
    first = _return_map(law, fresh, rng.uniform(-3, 3, n) * -t_n / ps, t_n, ps, length)
    used = {k: np.asarray(v, dtype=float).copy() for k, v in law.trial_history(first).items()}
    _assert(set(used) == set(fields),
            f"{law!r}: trial_history() gives the fields {sorted(used)}, history_fields() "
            f"{sorted(fields)}")
    counts = np.zeros(2, dtype=int)  # tangent checks made on sticking and slipping contacts
    for committed in (fresh, used):
        dgs = rng.uniform(-3, 3, n) * -t_n / ps
        trial = _check_trial(law, committed, dgs, t_n, ps, pn, length, fields)
        _check_vectorized(law, committed, dgs, t_n, ps, length, trial)
        _check_stick(law, committed, dgs, t_n, ps, length, trial, fields)
        _check_physics(law, committed, dgs, t_n, pn, ps, trial)
        counts += _check_tangent(law, committed, dgs, t_n, pn, ps, length, trial, rtol)
    _assert(counts[0] > 0 and counts[1] > 0,
            f"{law!r}: of the sampled trials {counts[0]} stuck and {counts[1]} slipped away "
            "from the yield surface; the tangent must be checked on both branches: give "
            "check_friction_law normal_forces where the law does both")
    _check_untouched_contacts(law, used, pn, ps, length)
    _check_pickle(law, used, t_n, ps, length)
    _check_rebuilt(law, used, t_n, ps, length)


def _check_untouched_contacts(law, committed, pn, ps, length):
    """Contacts without normal force (just closed, or closed within round-off): finite
    force, no slip resistance from nothing, and a finite tangent."""
    n = len(ps)
    zero = np.zeros(n)
    for dgs in (zero, np.full(n, 1e-6)):
        trial = _return_map(law, committed, dgs, zero, ps, length)
        k_ss, k_sn = law.tangent(trial, pn, ps)
        _assert(np.all(np.isfinite(trial.t_s)) and np.all(np.isfinite(k_ss))
                and np.all(np.isfinite(k_sn)),
                f"{law!r}: a contact with t_n = 0 gives a non-finite shear force or tangent "
                "(the solvers pass t_n = 0 for contacts that have just closed)")


def _return_map(law, committed, dgs, t_n, ps, length):
    """The law's return map as the contact element calls it (no faces: each contact is its
    own face, the rule a corner contact follows)."""
    kw = {"faces": None} if law.uses_faces else {}
    if law.uses_dt:
        kw["dt"] = CHECK_DT
    return law.return_map(committed, dgs, t_n, ps, length, **kw)


def _assert(ok, message):
    if not ok:
        raise AssertionError(message)


def _check_history_fields(law, n):
    fields = law.history_fields()
    _assert(isinstance(fields, dict) and all(isinstance(k, str) for k in fields),
            f"{law!r}: history_fields() must be a dict of field name to initial value")
    state = law.initial_state(n)
    _assert(set(state) == set(fields),
            f"{law!r}: initial_state() gives {sorted(state)}, history_fields() {sorted(fields)}")
    stray = sorted(set(law.kept_when_open()) - set(fields))
    _assert(not stray, f"{law!r}: kept_when_open() names {stray}, which history_fields() "
                       f"does not have ({sorted(fields)})")
    for k, v in state.items():
        v = np.asarray(v)
        _assert(v.dtype.kind == "f",
                f"{law!r}: initial_state({n})[{k!r}] has dtype {v.dtype}; history is carried "
                "as float arrays (keep a flag as 0.0 / 1.0)")
        _assert(v.shape == (n,) and np.all(np.isfinite(v)),
                f"{law!r}: initial_state({n})[{k!r}] must be {n} finite numbers, got shape "
                f"{v.shape}")
    return fields


def _check_trial(law, committed, dgs, t_n, ps, pn, length, fields):
    """A trial of the right shapes that leaves its inputs alone; its tangent too."""
    inputs = (committed, dgs, t_n, ps, length)
    before = copy.deepcopy(inputs)
    trial = _return_map(law, committed, dgs, t_n, ps, length)
    law.tangent(trial, pn, ps)
    law.stick(committed, dgs, ps)
    law.trial_history(trial)
    for name, a, b in zip(("committed history", "delta_g_s", "t_n", "shear_penalty",
                           "length"), before, inputs, strict=True):
        same = (all(np.array_equal(a[k], b[k]) for k in a) and set(a) == set(b)
                if isinstance(a, dict) else np.array_equal(a, b))
        _assert(same, f"{law!r}: a trial changed its input {name} (a trial must be built "
                      "from the committed history and leave it untouched: copy before writing)")
    _assert(isinstance(trial, FrictionTrial), f"{law!r}: return_map must return a FrictionTrial")
    n = len(dgs)
    for name in ("t_s", "slipping", "strength"):
        value = np.asarray(getattr(trial, name))
        _assert(value.shape == (n,), f"{law!r}: trial.{name} has shape {value.shape}, "
                                     f"expected ({n},): one value per contact")
    _assert(np.all(np.isfinite(trial.t_s)), f"{law!r}: non-finite shear force in a trial")
    state = law.trial_history(trial)
    _assert(set(state) == set(fields), f"{law!r}: a committed trial has the fields "
                                       f"{sorted(state)}, history_fields() {sorted(fields)}")
    return trial


def _check_vectorized(law, committed, dgs, t_n, ps, length, trial):
    """Each contact's result is the same evaluated alone as among all the others."""
    state = law.trial_history(trial)
    for i in range(0, len(dgs), max(1, len(dgs) // 8)):
        s = slice(i, i + 1)
        one = _return_map(law, {k: v[s] for k, v in committed.items()}, dgs[s], t_n[s], ps[s],
                             length[s])
        close = (np.allclose(one.t_s, trial.t_s[s], rtol=1e-12, atol=0.0)
                 and np.array_equal(one.slipping, trial.slipping[s])
                 and all(np.allclose(v, state[k][s], rtol=1e-12, atol=1e-300)
                         for k, v in law.trial_history(one).items()))
        _assert(close, f"{law!r}: contact {i} evaluated alone differs from the same contact "
                       "evaluated with the others (the law must be vectorized element-wise)")


def _check_stick(law, committed, dgs, t_n, ps, length, trial, fields):
    """On a sticking trial the stick branch gives the return map's force."""
    stick = law.stick(committed, dgs, ps)
    _assert(set(law.trial_history(stick)) == set(fields),
            f"{law!r}: stick() gives the fields {sorted(stick.state)}, history_fields() "
            f"{sorted(fields)}")
    held = ~np.asarray(trial.slipping)
    _assert(np.allclose(stick.t_s[held], trial.t_s[held], rtol=1e-10, atol=0.0),
            f"{law!r}: stick() and return_map() disagree on contacts that stick (legacy DDA "
            "uses stick() for a locked spring)")
    after_stick, after_trial = law.trial_history(stick), law.trial_history(trial)
    for k in fields:
        a, b = np.asarray(after_stick[k])[held], np.asarray(after_trial[k])[held]
        _assert(np.allclose(a, b, rtol=1e-9, atol=1e-12 * np.max(np.abs(b), initial=1.0)),
                f"{law!r}: on contacts that stick, the history field {k!r} after stick() "
                "differs from the one after return_map() (legacy DDA commits stick()'s: a "
                "flag such as 'sliding' must be reset there too)")


def _check_physics(law, committed, dgs, t_n, pn, ps, trial):
    """What friction is: a slipping contact's force no larger than its trial (the stick
    spring's force: slip relaxes the spring, it never stretches it; a strength that rises
    with slip or its rate stays below the trial) and of its sign (against the slip), and a
    stick spring that pushes back (d t_s / d g_s > 0). A law whose slip branch gave 1.5 times
    its strength, and one whose force pushed the slip along, passed the other checks: the
    first took Newton-Raphson to steps of 1e-7 s, the second slid a block 0.42 m down a 25
    degree slope at phi 30 degrees."""
    slipping = np.asarray(trial.slipping)
    t_s = np.asarray(trial.t_s, dtype=float)
    t_trial = np.asarray(law.stick(committed, dgs, ps).t_s, dtype=float)
    k_ss = np.asarray(law.tangent(trial, pn, ps)[0], dtype=float)
    _refuse(slipping & (np.abs(t_s) > np.abs(t_trial) * (1.0 + 1e-9) + 1e-12 * np.abs(t_n)),
            lambda i: f"{law!r}: a slipping contact carries {t_s[i]:.6g} N/m, more than its "
                      f"trial (stick spring) force {t_trial[i]:.6g} N/m: slip relaxes the "
                      f"spring (t_n = {t_n[i]:.4g})")
    _refuse(slipping & (t_s * t_trial < 0.0),
            lambda i: f"{law!r}: a slipping contact's force {t_s[i]:.6g} N/m has the other "
                      f"sign than its trial (stick spring) force {t_trial[i]:.6g} N/m: "
                      "friction must resist the slip")
    _refuse(~slipping & ~(k_ss > 0.0),
            lambda i: f"{law!r}: a sticking contact's d t_s / d g_s is {k_ss[i]:.6g}; a stick "
                      f"spring pushes back (positive, the shear penalty {ps[i]:.6g} N/m for a "
                      "Coulomb law)")


def _refuse(bad: np.ndarray, message) -> None:
    """AssertionError with ``message(i)`` of the first contact in ``bad``, and how many."""
    if bad.any():
        i = int(np.flatnonzero(bad)[0])
        raise AssertionError(f"{message(i)} ({np.count_nonzero(bad)} of {len(bad)} contacts)")


def _check_tangent(law, committed, dgs, t_n, pn, ps, length, trial, rtol):
    """d t_s / d g_s and d t_s / d g_n against central differences, away from kinks."""
    k_ss, k_sn = (np.asarray(a, dtype=float) for a in law.tangent(trial, pn, ps))
    g_n = t_n / pn
    h_s = 1e-6 * np.abs(t_n) / ps
    h_n = 1e-6 * np.abs(g_n)

    def at(dgs_, g_n_):
        return _return_map(law, committed, dgs_, pn * g_n_, ps, length)

    plus_s, minus_s = at(dgs + h_s, g_n), at(dgs - h_s, g_n)
    plus_n, minus_n = at(dgs, g_n + h_n), at(dgs, g_n - h_n)
    fd_s = (plus_s.t_s - minus_s.t_s) / (2 * h_s)
    fd_n = (plus_n.t_s - minus_n.t_s) / (2 * h_n)
    slipping = np.asarray(trial.slipping)
    # a branch switch inside the difference has no derivative: skip those contacts
    smooth = np.ones(len(dgs), dtype=bool)
    for other in (plus_s, minus_s, plus_n, minus_n):
        smooth &= np.asarray(other.slipping) == slipping
    bad_s = np.abs(k_ss - fd_s) > rtol * np.abs(fd_s) + 1e-6 * ps
    bad_n = np.abs(k_sn - fd_n) > rtol * np.abs(fd_n) + 1e-6 * pn
    for name, bad, analytic, fd in (("d t_s / d g_s", bad_s, k_ss, fd_s),
                                    ("d t_s / d g_n", bad_n, k_sn, fd_n)):
        wrong = np.flatnonzero(bad & smooth)
        if len(wrong):
            i = int(wrong[0])
            branch = "slipping" if slipping[i] else "sticking"
            raise AssertionError(
                f"{law!r}: tangent {name} of a {branch} contact is {analytic[i]:.6g}, finite "
                f"differences give {fd[i]:.6g} ({len(wrong)} of {len(dgs)} contacts wrong; "
                f"t_n = {t_n[i]:.4g}, delta_g_s = {dgs[i]:.4g})")
    return np.array([np.count_nonzero(smooth & ~slipping), np.count_nonzero(smooth & slipping)])


def _check_rebuilt(law, committed, t_n, ps, length):
    """The law rebuilt from its constructor's parameters, read back as its attributes of the
    same names, gives the same forces (how a checkpoint keeps a law, with its class's
    import path: :func:`dda.io.scene_data.law_to_data`)."""
    from dda.registry import parameters

    cls = type(law)
    missing = [p for p in parameters(cls) if not hasattr(law, p)]
    _assert(not missing,
            f"{law!r} does not keep its constructor parameter(s) {missing} as attributes of "
            "the same names; a checkpoint rebuilds a law from them")
    copy_ = cls(**{p: getattr(law, p) for p in parameters(cls)})
    dgs = 2.0 * -t_n / ps
    a = _return_map(law, committed, dgs, t_n, ps, length)
    b = _return_map(copy_, committed, dgs, t_n, ps, length)
    _assert(np.array_equal(a.t_s, b.t_s) and np.array_equal(a.slipping, b.slipping),
            f"{law!r}: the law rebuilt from its parameters (as a checkpoint rebuilds it) gives "
            "other forces than the law")


def _check_pickle(law, committed, t_n, ps, length):
    try:
        copy_ = pickle.loads(pickle.dumps(law))
    except Exception as exc:  # pickle raises several types
        raise AssertionError(f"{law!r} cannot be pickled ({type(exc).__name__}: {exc}); "
                             "parallel sweeps copy laws by pickling") from None
    dgs = 2.0 * -t_n / ps
    a = _return_map(law, committed, dgs, t_n, ps, length)
    b = _return_map(copy_, committed, dgs, t_n, ps, length)
    _assert(np.array_equal(a.t_s, b.t_s) and np.array_equal(a.slipping, b.slipping),
            f"{law!r}: a pickled copy of the law gives other forces than the law")
