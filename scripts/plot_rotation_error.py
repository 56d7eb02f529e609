#!/usr/bin/python3
"""Plot the Taylor y-rotation error curves ([2] Fig. 3) from the CSV written by
rotation_error_csv (scripts/rotation_error_csv.cpp); scripts/plot_rotation_error.sh runs
both:

    build/tests/rotation_error_csv /tmp/rotation-error.csv
    /usr/bin/python3 scripts/plot_rotation_error.py /tmp/rotation-error.csv docs/rotation-error.png

Layout as in the paper: one column per order (5 and 8), rows = maximum error over
unit-length vectors, average error (mean singular value), error for a unit-length Phong
lobe cos^7 along z. Each panel shows the 1st, 1.5th and 2nd order expansions. The y axis
is logarithmic (the paper's text does not state its scale; on a log axis the b^2 / b^3
growth of the orders and the tolerance crossings used by the auto method are readable).
"""
import csv
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

METHODS = [("taylor1", "1st order", "-"), ("taylor1.5", "1.5th order", "--"), ("taylor2", "2nd order", ":")]
ROWS = [("max_error", "maximum error"), ("mean_error", "average error"), ("phong7_error", "Phong lobe cos$^7$")]


def main(argv):
    if len(argv) != 3:
        sys.stderr.write("usage: plot_rotation_error.py DATA.csv OUT.png\n")
        return 2
    data = {}
    with open(argv[1], newline="") as f:
        for row in csv.DictReader(f):
            key = (int(row["order"]), row["method"])
            data.setdefault(key, []).append({k: float(v) for k, v in row.items() if k != "method"})
    orders = sorted({k[0] for k in data})
    if not orders:
        sys.stderr.write(f"{argv[1]}: no data\n")
        return 1

    # Deterministic output: fixed size, dpi and metadata without a date.
    fig, axes = plt.subplots(len(ROWS), len(orders), figsize=(4.2 * len(orders), 3.0 * len(ROWS)),
                             sharex=True, squeeze=False)
    for c, order in enumerate(orders):
        for r, (column, label) in enumerate(ROWS):
            ax = axes[r][c]
            for method, name, style in METHODS:
                pts = [p for p in data.get((order, method), []) if p["beta_deg"] > 0]
                ax.semilogy([p["beta_deg"] for p in pts], [max(p[column], 1e-17) for p in pts],
                            style, color="black", label=name)
            ax.set_xlim(0, 40)
            ax.grid(True, which="major", alpha=0.3)
            if r == 0:
                ax.set_title(f"order N = {order}")
            if c == 0:
                ax.set_ylabel(label)
            if r == len(ROWS) - 1:
                ax.set_xlabel("tilt b (degrees)")
            if r == 0 and c == 0:
                ax.legend(loc="lower right", fontsize=8)
    fig.suptitle("Taylor y-rotation error E(b) (cf. [2] Fig. 3)")
    fig.tight_layout()
    fig.savefig(argv[2], dpi=100, metadata={"Software": None})
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
