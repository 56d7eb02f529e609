#!/usr/bin/python3
"""Sparsity figures of the ZHF lobe tables for docs/lobes.md ([1] Table I, Fig. 3).

    /usr/bin/python3 scripts/plot_lobes.py                      # figures + markdown table
    /usr/bin/python3 scripts/plot_lobes.py --check --shtool build/shtool   # self-check only

Reads every shipped tables/zhf-bands-*.shtb (per-band searches; whatever bands exist) and
tables/zhf-shared-N*.shtb (shared lobes, Sec. 6) with tests/read_table_numpy.py, and writes
  docs/lobes-sparsity.png  spy plots of A^_l = Y_l^-1 (rows m = -l..l, columns d = lobes):
                           every band of the per-band tables, and bands 1..7 of shared N = 8;
  docs/lobes-fig3.png      paper Fig. 3: sparsity of random lobe sets drawn from the same
                           candidates the search uses, against the searched sets, per band
                           and for shared orders N;
and prints the numbers as a markdown table on stdout.

Everything is recomputed here with numpy, independently of the C++ code:
  - real SH in the convention of docs/conventions.md, through the derivatives of the Legendre
    polynomials (P_l^m = (-1)^m (1 - z^2)^(m/2) d^m P_l / dz^m, Condon-Shortley phase) and
    (x + i y)^m for the azimuth, exact at the poles (the C++ uses a recurrence instead);
    `--check` compares it with `shtool eval`;
  - the candidates (docs/lobes.md, "Candidates"): theta = zeros of P_l^m(cos t),
    m = 0..l-1, of the band itself (numpy's Legendre roots polished by Newton in t) plus
    the poles; phi = j pi / (2m), m = 1..l; shared order N uses the candidates of band N-1;
  - A^_l = inv(Y_l), an entry is zero when |a| < 1e-9 (paper Sec. 5), a set is valid when
    cond_2(Y_l) <= 1e4 (the search's default bound; singular sets are invalid). The
    searched tables are recomputed from their directions and must reproduce the stored
    zero counts exactly (the script fails otherwise).
Random sets: each direction draws its theta and phi uniformly from the candidates (as the
GA's initial population does); invalid draws are omitted (as in the paper's Fig. 3) and
counted; `--samples` valid sets per band / order with a fixed `--seed`, so the PNGs are
reproducible (PNG metadata carries no date or version).
"""
import argparse
import glob
import json
import math
import os
import re
import subprocess
import sys
from fractions import Fraction

import numpy as np
from numpy.polynomial import legendre as npleg

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(ROOT, "tests"))
from read_table_numpy import read_table  # noqa: E402

ZERO_THRESHOLD = 1e-9    # [1] Sec. 5; src/offline/lobes/lobes.h kZeroThreshold
MAX_COND = 1e4           # src/offline/lobes/lobes.h kDefaultMaxCond (what the search accepts)
SINGULAR_RCOND = 1e-12   # src/offline/lobes/lobes.h kSingularRcond
# [1] Table I (per-band sparsity, %), l = 2..18.
PAPER_TABLE_I = dict(zip(range(2, 19), [64, 67, 62, 53, 49, 46, 42, 39, 38, 38, 37, 37, 36, 36, 36, 35, 35]))
# [1] Fig. 3 caption, N = 8: random mean, random max, GA result (%).
PAPER_FIG3_N8 = (3, 29, 45)
# [1]'s supplemental data (transcribed) as a nested shared set, N = 4..8 (%).
TRANSCRIBED_SHARED = {4: 55.4, 5: 51.6, 6: 50.4, 7: 44.7, 8: 42.7}
# Agreement of this script's SH with `shtool eval`: both double, different algorithms
# (Legendre-series derivatives here, a three-term recurrence there); values are O(1) and
# the worst rounding of either is a few hundred ulps at l = 18, far below 1e-12.
SH_CHECK_TOLERANCE = 1e-12
# A shipped theta must be one of our candidates to this accuracy (both are polished
# zeros of the same polynomials: a few ulps apart).
CANDIDATE_MATCH = 1e-12


class ScriptError(Exception):
    pass


# ---------------------------------------------------------------------------
# Real SH of one band (docs/conventions.md).

def _legendre_derivative_coeffs(l, m):
    c = np.zeros(l + 1)
    c[l] = 1.0
    return npleg.legder(c, m) if m > 0 else c


def _norm(l, m):
    # K_l^m = sqrt((2l+1)/(4 pi) (l-m)!/(l+m)!), the factorial ratio exact as a fraction.
    return math.sqrt((2 * l + 1) / (4 * math.pi) * float(Fraction(math.factorial(l - m), math.factorial(l + m))))


def band_sh(l, dirs):
    """y_l^m(w) for m = -l..l: array [len(dirs), 2l+1]. dirs: unit vectors [n, 3]."""
    dirs = np.asarray(dirs, dtype=float).reshape(-1, 3)
    x, y, z = dirs[:, 0], dirs[:, 1], dirs[:, 2]
    out = np.empty((len(dirs), 2 * l + 1))
    xy = (x + 1j * y)
    power = np.ones(len(dirs), dtype=complex)  # (x + i y)^m = sin^m t e^{i m p}
    for m in range(0, l + 1):
        if m > 0:
            power = power * xy
        # P_l^m(z) / sin^m t with the Condon-Shortley phase.
        q = (-1) ** m * npleg.legval(z, _legendre_derivative_coeffs(l, m)) * _norm(l, m)
        if m == 0:
            out[:, l] = q
        else:
            out[:, l + m] = math.sqrt(2) * q * power.real
            out[:, l - m] = math.sqrt(2) * q * power.imag
    return out


def direction(theta, phi):
    """Unit vectors of (t, p), exact at the poles (as src/offline/lobes lobe_direction)."""
    theta, phi = np.broadcast_arrays(np.asarray(theta, dtype=float), np.asarray(phi, dtype=float))
    st = np.sin(theta)
    ct = np.cos(theta)
    north, south = theta == 0.0, theta == math.pi
    st = np.where(north | south, 0.0, st)
    ct = np.where(north, 1.0, np.where(south, -1.0, ct))
    return np.stack([st * np.cos(phi), st * np.sin(phi), ct], axis=-1)


# ---------------------------------------------------------------------------
# Candidates (docs/lobes.md "Candidates", default `band` set).

def legendre_zeros_theta(l, m):
    """Polar angles of the interior zeros of P_l^m(cos t) (= zeros of d^m P_l / dz^m)."""
    if l - m <= 0:
        return []
    c = _legendre_derivative_coeffs(l, m)
    dc = npleg.legder(c)
    roots = np.sort(np.real(npleg.legroots(c)))
    out = []
    for z0 in roots:
        t = math.acos(min(1.0, max(-1.0, z0)))
        # Newton in t: f(t) = D(cos t), f'(t) = -sin t D'(cos t); in t the zeros near the
        # poles keep their relative accuracy.
        for _ in range(30):
            step = npleg.legval(math.cos(t), c) / (-math.sin(t) * npleg.legval(math.cos(t), dc))
            t -= step
            if abs(step) < 1e-17:
                break
        out.append(t)
    return out


def theta_candidates(l, pooled=False):
    v = [0.0, math.pi]
    for k in (range(1, l + 1) if pooled else [l]):
        for m in range(k):  # P_k^k = sin^k t has no interior zero
            v.extend(legendre_zeros_theta(k, m))
    v = sorted(v)
    out = []
    for t in v:  # dedupe zeros shared by several (k, m) (e.g. t = pi/2)
        if not out or t - out[-1] > 1e-12:
            out.append(t)
    return np.array(out)


def phi_candidates(l):
    fr = sorted({Fraction(j, 2 * m) for m in range(1, l + 1) for j in range(4 * m)})
    return np.array([math.pi * f.numerator / f.denominator for f in fr])


# ---------------------------------------------------------------------------
# Sparsity of A^ = Y^-1.

def analyze(y):
    """(valid, cond, zero mask of A^) for a stack of Y matrices [..., n, n]."""
    s = np.linalg.svd(y, compute_uv=False)
    smin, smax = s[..., -1], s[..., 0]
    with np.errstate(divide="ignore", invalid="ignore"):
        cond = np.where(smin > 0, smax / smin, np.inf)
    valid = (smin >= SINGULAR_RCOND * smax) & (cond <= MAX_COND)
    a = np.zeros_like(y)
    if valid.any():
        a[valid] = np.linalg.inv(y[valid])
    return valid, cond, np.abs(a) < ZERO_THRESHOLD


def random_band(l, samples, rng, batch=2000, max_draws=400000):
    """Sparsity of `samples` valid random lobe sets of band l, and the number of draws."""
    th, ph = theta_candidates(l), phi_candidates(l)
    n = 2 * l + 1
    grid = band_sh(l, direction(th[:, None], ph[None, :]).reshape(-1, 3))  # [nt*np, n]
    found, draws = [], 0
    while len(found) < samples and draws < max_draws:
        ti = rng.integers(0, len(th), size=(batch, n))
        pi = rng.integers(0, len(ph), size=(batch, n))
        y = grid[ti * len(ph) + pi]
        valid, _, zero = analyze(y)
        for b in range(batch):
            draws += 1
            if valid[b]:
                found.append(zero[b].mean())
                if len(found) == samples:
                    break
    return np.array(found), draws


def random_shared(order, samples, rng, batch=2000, max_draws=400000):
    """Random nested sets of 2N-1 directions from band N-1's candidates: sparsity over
    A^_k, k = 2..N-1 (bands 1..N-1 must all be valid), and the number of draws."""
    top = order - 1
    th, ph = theta_candidates(top), phi_candidates(top)
    nd = 2 * order - 1
    dirs = direction(th[:, None], ph[None, :]).reshape(-1, 3)
    grids = {k: band_sh(k, dirs) for k in range(1, order)}
    entries = sum((2 * k + 1) ** 2 for k in range(2, order))
    found, draws = [], 0
    while len(found) < samples and draws < max_draws:
        idx = rng.integers(0, len(th), size=(batch, nd)) * len(ph) + rng.integers(0, len(ph), size=(batch, nd))
        ok = np.ones(batch, dtype=bool)
        zeros = np.zeros(batch)
        for k in range(1, order):
            valid, _, zero = analyze(grids[k][idx[:, :2 * k + 1]])
            ok &= valid
            if k >= 2:
                zeros += zero.sum(axis=(1, 2))
        for b in range(batch):
            draws += 1
            if ok[b]:
                found.append(zeros[b] / entries)
                if len(found) == samples:
                    break
    return np.array(found), draws


# ---------------------------------------------------------------------------
# Shipped tables.

def load_lobe_table(path):
    """Bands of a zhf-lobes table, recomputed from its directions: list of dicts."""
    header, a = read_table(path)
    if header.get("kind") != "zhf-lobes":
        raise ScriptError(f"{path}: not a zhf-lobes table (kind {header.get('kind')!r})")
    bands = []
    flat = 0
    for i, l in enumerate(a["bands"].tolist()):
        n = 2 * l + 1
        off = int(a["direction_offset"][i])
        dirs = a["directions"][off:off + n]
        stored = a["a_hat"][flat:flat + n * n].reshape(n, n)
        flat += n * n
        if l == 0:
            bands.append(dict(l=0, zero=np.zeros((1, 1), bool), cond=1.0, theta=a["theta"][off:off + n],
                              phi=a["phi"][off:off + n], cond_stored=float(a["cond"][i])))
            continue
        valid, cond, zero = analyze(band_sh(l, dirs)[None])
        zero = zero[0]  # inv(Y[d][m]) is indexed [m][d], the table's a_hat layout
        if not valid[0]:
            raise ScriptError(f"{path}: band {l}: Y_l recomputed from the directions is singular or cond > {MAX_COND:g}")
        if int(zero.sum()) != int(a["zeros"][i]) or not np.array_equal(zero, stored == 0.0):
            raise ScriptError(f"{path}: band {l}: recomputed A^ has {int(zero.sum())} zeros, the table "
                              f"{int(a['zeros'][i])} (or a different pattern)")
        bands.append(dict(l=l, zero=zero, cond=float(cond[0]), cond_stored=float(a["cond"][i]),
                          theta=a["theta"][off:off + n], phi=a["phi"][off:off + n]))
    return header, bands


def band_tables(tables_dir):
    out = {}
    paths = sorted(glob.glob(os.path.join(tables_dir, "zhf-bands-*.shtb")))
    for p in paths:
        _, bands = load_lobe_table(p)
        for b in bands:
            b["source"] = os.path.basename(p)
            out.setdefault(b["l"], b)  # the first file (sorted name) wins on a repeated band
    return dict(sorted(out.items()))


def shared_tables(tables_dir):
    out = {}
    for p in glob.glob(os.path.join(tables_dir, "zhf-shared-N*.shtb")):
        m = re.search(r"zhf-shared-N(\d+)\.shtb$", p)
        if not m:
            continue
        header, bands = load_lobe_table(p)
        order = int(m.group(1))
        if len(bands) != order:
            raise ScriptError(f"{p}: {len(bands)} bands, expected {order}")
        zeros = sum(int(b["zero"].sum()) for b in bands if b["l"] >= 2)
        entries = sum((2 * b["l"] + 1) ** 2 for b in bands if b["l"] >= 2)
        restarts = []
        for s in header.get("meta", {}).get("searches", []):
            restarts.extend(s.get("restart_sparsity", []))
        out[order] = dict(order=order, bands=bands, sparsity=zeros / entries, zeros=zeros, entries=entries,
                          max_cond=max(b["cond"] for b in bands), restarts=restarts, source=os.path.basename(p))
    return dict(sorted(out.items()))


def check_candidates(per_band, shared):
    """Every shipped direction must be a candidate (theta and phi) of its band / order."""
    def check(where, l, theta, phi):
        th, ph = theta_candidates(l), phi_candidates(l)
        for t, p in zip(theta, phi):
            if np.min(np.abs(th - t)) > CANDIDATE_MATCH:
                raise ScriptError(f"{where}: theta {t!r} is not a band-{l} candidate (nearest "
                                  f"{th[np.argmin(np.abs(th - t))]!r})")
            if t not in (0.0, math.pi) and np.min(np.abs(ph - p)) > CANDIDATE_MATCH:
                raise ScriptError(f"{where}: phi {p!r} is not a band-{l} candidate")
    for l, b in per_band.items():
        check(f"{b['source']} band {l}", l, b["theta"], b["phi"])
    for n, s in shared.items():
        top = s["bands"][-1]
        check(f"{s['source']}", n - 1, top["theta"], top["phi"])


def check_against_shtool(exe, order=19):
    """Compare band_sh with `shtool eval` at a few directions, bands 0..order-1."""
    rng = np.random.default_rng(5)
    dirs = [np.array([0.0, 0.0, 1.0]), np.array([0.0, 0.0, -1.0]), np.array([1.0, 0.0, 0.0]),
            np.array([0.3, -0.5, 0.8])]
    for _ in range(4):
        v = rng.normal(size=3)
        dirs.append(v / np.linalg.norm(v))
    worst = 0.0
    for w in dirs:
        arg = ",".join(repr(float(c)) for c in w)
        try:
            r = subprocess.run([exe, "eval", "--order", str(order), "--dir", arg], capture_output=True, text=True,
                               timeout=60)
        except OSError as e:
            raise ScriptError(f"cannot run {exe}: {e}")
        if r.returncode != 0:
            raise ScriptError(f"{exe} eval --dir {arg} failed ({r.returncode}): {r.stderr.strip()}")
        try:
            values = np.array(json.loads(r.stdout)["values"], dtype=float)
        except (ValueError, KeyError) as e:
            raise ScriptError(f"{exe} eval: unreadable output ({e}): {r.stdout[:200]!r}")
        if values.size != order * order:
            raise ScriptError(f"{exe} eval: {values.size} values, expected {order * order}")
        # shtool normalises --dir; so do we (the printed repr is exact anyway).
        wn = w / np.linalg.norm(w)
        for l in range(order):
            mine = band_sh(l, wn[None])[0]
            theirs = values[l * l:(l + 1) * (l + 1)]
            err = float(np.max(np.abs(mine - theirs)))
            worst = max(worst, err)
            if err > SH_CHECK_TOLERANCE:
                raise ScriptError(f"SH of band {l} at {arg}: script {mine.tolist()} vs shtool eval "
                                  f"{theirs.tolist()}: max difference {err:.3g} > {SH_CHECK_TOLERANCE:g}")
    return worst, len(dirs)


# ---------------------------------------------------------------------------
# Figures.

def savefig(fig, path):
    # No date or version in the metadata: the same inputs give the same bytes.
    fig.savefig(path, dpi=110, metadata={"Software": None})


def plot_sparsity(per_band, shared, path, shared_order=8):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    panels = [(f"l = {l}", b, f"{100 * b['zero'].mean():.1f}%, cond {b['cond']:.3g}") for l, b in per_band.items()]
    shared_panels = []
    if shared_order in shared:
        for b in shared[shared_order]["bands"][1:]:
            shared_panels.append((f"N = {shared_order}, k = {b['l']}", b,
                                  f"{100 * b['zero'].mean():.1f}%, cond {b['cond']:.3g}"))
    ncols = 7  # shared N = 8 shows bands 1..7: one row
    rows_a = (len(panels) + ncols - 1) // ncols
    rows_b = (len(shared_panels) + ncols - 1) // ncols
    nrows = rows_a + rows_b
    fig, axes = plt.subplots(nrows, ncols, figsize=(2.6 * ncols, 2.9 * nrows), squeeze=False)
    for ax in axes.flat:
        ax.axis("off")
    def draw(ax, title, b, sub):
        nz = ~b["zero"]
        ax.axis("on")
        ax.imshow(nz, cmap="Greys", vmin=0, vmax=1.6, interpolation="nearest")
        n = nz.shape[0]
        ax.set_xticks([0, n - 1])
        ax.set_yticks([0, n - 1])
        ax.set_yticklabels([f"m={-(n // 2)}", f"m={n // 2}"], fontsize=6)
        ax.set_xticklabels(["d=0", f"d={n - 1}"], fontsize=6)
        ax.set_title(f"{title}\n{sub}", fontsize=8)
    for i, (t, b, s) in enumerate(panels):
        draw(axes[i // ncols][i % ncols], t, b, s)
    for i, (t, b, s) in enumerate(shared_panels):
        draw(axes[rows_a + i // ncols][i % ncols], t, b, s)
    fig.suptitle("Non-zeros (dark) of A^_l = Y_l^-1: rows m = -l..l, columns = lobes d.  "
                 f"Per-band tables (zhf-bands-*), then shared N = {shared_order} (bands k of one nested set)",
                 fontsize=9)
    fig.tight_layout(rect=(0, 0, 1, 0.97))
    savefig(fig, path)
    plt.close(fig)


def plot_fig3(band_rows, shared_rows, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(12, 4.6))
    for ax, rows, key, xlabel, title in (
            (axes[0], band_rows, "l", "band l", "Per band"),
            (axes[1], shared_rows, "N", "order N", "Shared lobes (bands 2..N-1 counted)")):
        x = np.array([r[key] for r in rows])
        have = [r for r in rows if r["random"].size]
        xr = np.array([r[key] for r in have])
        if have:
            p10 = np.array([np.percentile(r["random"], 10) for r in have]) * 100
            p90 = np.array([np.percentile(r["random"], 90) for r in have]) * 100
            ax.fill_between(xr, p10, p90, color="0.85", label="random: 10-90th percentile")
            ax.plot(xr, [100 * r["random"].mean() for r in have], "o-", color="0.45", ms=4, label="random: mean")
            ax.plot(xr, [100 * r["random"].max() for r in have], "v--", color="0.45", ms=4, label="random: max")
        ax.plot(x, [100 * r["searched"] for r in rows], "s-", color="black", ms=5, label="search (shipped tables)")
        if key == "l":
            pl = [l for l in x if l in PAPER_TABLE_I]
            ax.plot(pl, [PAPER_TABLE_I[l] for l in pl], "x:", color="tab:red", label="paper Table I")
        else:
            rs = [r for r in rows if r.get("restarts")]
            for i, r in enumerate(rs):
                ax.plot([r["N"]] * len(r["restarts"]), [100 * v for v in r["restarts"]], "_", color="tab:blue",
                        ms=8, alpha=0.6, label="search: each restart" if i == 0 else None)
            tn = [n for n in x if n in TRANSCRIBED_SHARED]
            ax.plot(tn, [TRANSCRIBED_SHARED[n] for n in tn], "d:", color="tab:green", ms=5,
                    label="transcribed supplemental table")
            if 8 in set(x.tolist()):
                mean, mx, ga = PAPER_FIG3_N8
                ax.plot([8, 8, 8], [mean, mx, ga], "x", color="tab:red", ms=8, mew=2,
                        label="paper Fig. 3 at N = 8 (random mean, max; GA)")
        ax.set_xlabel(xlabel)
        ax.set_ylabel("sparsity of A^ (% of entries with |a| < 1e-9)")
        ax.set_xticks(x)
        ax.set_ylim(0, 75)
        ax.grid(True, alpha=0.3)
        ax.set_title(title, fontsize=10)
        ax.legend(fontsize=7, loc="upper right")
    fig.suptitle("Random lobe sets from the search's candidates vs. the searched sets (cf. [1] Fig. 3); "
                 "random sets with cond(Y) > 1e4 or singular are omitted", fontsize=9)
    fig.tight_layout(rect=(0, 0, 1, 0.95))
    savefig(fig, path)
    plt.close(fig)


# ---------------------------------------------------------------------------

def markdown(band_rows, shared_rows, samples, seed):
    lines = [f"Random: {samples} valid sets per row, seed {seed}; 'valid' = share of draws with cond(Y) <= 1e4 "
             "(singular or worse-conditioned draws are omitted, as in the paper's Fig. 3).", "",
             "| l | random mean | random median | random max | valid draws | search | cond (search) | paper Table I |",
             "|---|---|---|---|---|---|---|---|"]
    for r in band_rows:
        rnd = r["random"]
        lines.append(f"| {r['l']} | {100 * rnd.mean():.1f}% | {100 * np.median(rnd):.1f}% | {100 * rnd.max():.1f}% | "
                     f"{100 * len(rnd) / r['draws']:.1f}% | **{100 * r['searched']:.1f}%** | {r['cond']:.3g} | "
                     f"{PAPER_TABLE_I.get(r['l'], '-')}% |")
    lines += ["", "| N | random mean | random median | random max | valid draws | search | max cond (search) | "
              "transcribed table | paper Fig. 3 |", "|---|---|---|---|---|---|---|---|---|"]
    for r in shared_rows:
        rnd = r["random"]
        paper = (f"random mean ~{PAPER_FIG3_N8[0]}%, max ~{PAPER_FIG3_N8[1]}%, GA {PAPER_FIG3_N8[2]}%"
                 if r["N"] == 8 else "-")
        tr = f"{TRANSCRIBED_SHARED[r['N']]}%" if r["N"] in TRANSCRIBED_SHARED else "-"
        lines.append(f"| {r['N']} | {100 * rnd.mean():.1f}% | {100 * np.median(rnd):.1f}% | {100 * rnd.max():.1f}% | "
                     f"{100 * len(rnd) / r['draws']:.1f}% | **{100 * r['searched']:.1f}%** | {r['cond']:.3g} | {tr} | "
                     f"{paper} |")
    return "\n".join(lines)


def main(argv):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--tables", default=os.path.join(ROOT, "tables"), help="directory of the zhf-*.shtb tables")
    ap.add_argument("--out-dir", default=os.path.join(ROOT, "docs"), help="where the PNGs go")
    ap.add_argument("--samples", type=int, default=200, help="valid random sets per band / order")
    ap.add_argument("--seed", type=int, default=1, help="seed of the random sets")
    ap.add_argument("--json", help="also write the numbers as JSON")
    ap.add_argument("--check", action="store_true",
                    help="self-check only (SH vs `shtool eval`, tables vs recomputation, candidates); no figures")
    ap.add_argument("--shtool", help="shtool executable for the SH check (with --check)")
    args = ap.parse_args(argv[1:])
    if args.samples < 1:
        ap.error("--samples must be >= 1")
    try:
        per_band = band_tables(args.tables)
        shared = shared_tables(args.tables)
        if not per_band and not shared:
            raise ScriptError(f"{args.tables}: no zhf-bands-*.shtb or zhf-shared-N*.shtb tables")
        check_candidates(per_band, shared)
        if args.check:
            if args.shtool:
                worst, ndirs = check_against_shtool(args.shtool)
                print(f"SH: max |script - shtool eval| = {worst:.3g} over {ndirs} directions, bands 0..18")
            print(f"tables: {len(per_band)} bands, {len(shared)} shared orders recomputed; zero counts and "
                  "patterns match, every direction is a candidate")
            return 0

        band_rows = []
        for l, b in per_band.items():
            rnd, draws = random_band(l, args.samples, np.random.default_rng([args.seed, 0, l]))
            band_rows.append(dict(l=l, random=rnd, draws=draws, searched=float(b["zero"].mean()), cond=b["cond"]))
            print(f"band {l}: {len(rnd)} valid of {draws} draws", file=sys.stderr)
        shared_rows = []
        for n, s in shared.items():
            rnd, draws = random_shared(n, args.samples, np.random.default_rng([args.seed, 1, n]))
            shared_rows.append(dict(N=n, random=rnd, draws=draws, searched=s["sparsity"], cond=s["max_cond"],
                                    restarts=s["restarts"]))
            print(f"shared N = {n}: {len(rnd)} valid of {draws} draws", file=sys.stderr)
        for r in band_rows + shared_rows:
            if r["random"].size == 0:
                raise ScriptError(f"no valid random set for {'l = ' + str(r['l']) if 'l' in r else 'N = ' + str(r['N'])}"
                                  f" in {r['draws']} draws")
        os.makedirs(args.out_dir, exist_ok=True)
        plot_sparsity(per_band, shared, os.path.join(args.out_dir, "lobes-sparsity.png"))
        plot_fig3(band_rows, shared_rows, os.path.join(args.out_dir, "lobes-fig3.png"))
        print(markdown(band_rows, shared_rows, args.samples, args.seed))
        if args.json:
            def row(r):
                return {k: (v.tolist() if isinstance(v, np.ndarray) else v) for k, v in r.items()}
            with open(args.json, "w") as f:
                json.dump({"bands": [row(r) for r in band_rows], "shared": [row(r) for r in shared_rows]}, f)
    except ScriptError as e:
        print(f"plot_lobes.py: error: {e}", file=sys.stderr)
        return 1
    except (OSError, ValueError, KeyError) as e:
        print(f"plot_lobes.py: error: {type(e).__name__}: {e}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
