"""Plots of lsmbs results with matplotlib (headless: set MPLBACKEND=Agg or call
matplotlib.use("Agg") before importing pyplot).

    g = lsmbs.geometry(case)
    lsmbs.plot.design(g["plate"])                  # μ_e and the zero contour of the level set
    lsmbs.plot.history(lsmbs.simulate(case), ["tip_deviation"])
    lsmbs.plot.convergence(lsmbs.optimize(case)["history"])
    lsmbs.plot.gradients({"direct": r1, "fd": r2}, "average_tip_deviation")

Every function draws on `ax` (a new figure when None) and returns the axes.
"""
import numpy as np


def _text(s):
    """A name as matplotlib text, never markup: a '$' pair would start mathtext (a name such as
    'a$b$c' failed to draw)."""
    return str(s).replace("$", r"\$")


def _axes(ax):
    if ax is not None:
        return ax
    import matplotlib.pyplot as plt
    return plt.figure(figsize=(8, 4.5)).add_subplot()


def design(body, ax=None, cmap="Greys", contour=True, colorbar=True):
    """μ_e of a designed body (a value of lsmbs.geometry(case)) in its body frame, with the
    features' boundary φ = 0 (nodal level set, linear on the triangles of a fan over each cell)."""
    from matplotlib.collections import PolyCollection
    import matplotlib.tri as mtri
    ax = _axes(ax)
    nodes, cells = body["nodes"], body["cells"]
    pc = PolyCollection([nodes[c] for c in cells], array=body["mu"], cmap=cmap,
                        edgecolors="face")
    pc.set_clim(0, 1)
    ax.add_collection(pc)
    if contour:
        tris = np.array([[c[0], c[k], c[k + 1]] for c in cells for k in range(1, len(c) - 1)])
        ax.tricontour(mtri.Triangulation(nodes[:, 0], nodes[:, 1], tris), body["phi"], levels=[0.0],
                      colors="tab:red", linewidths=1.0)
    ax.set_xlim(nodes[:, 0].min(), nodes[:, 0].max())
    ax.set_ylim(nodes[:, 1].min(), nodes[:, 1].max())
    ax.set_aspect("equal")
    ax.set_xlabel("x [m] (body frame)")
    ax.set_ylabel("y [m]")
    ax.set_title(f"μ_e, mass {body['mass']:.6g} kg; red: φ = 0")
    if colorbar:
        ax.figure.colorbar(pc, ax=ax, label="μ_e (volume fraction)", shrink=0.8)
    return ax


def history(result, columns=None, ax=None):
    """Measured histories of a simulation (lsmbs.simulate) against time."""
    ax = _axes(ax)
    if isinstance(columns, str):
        columns = [columns]
    for c in columns or result.columns:
        ax.plot(result.times, result.column(c), label=_text(c))
    ax.set_xlabel("t [s]")
    ax.legend()
    ax.grid(True, alpha=0.3)
    return ax


def convergence(evaluations, ax=None):
    """Objective and largest relative constraint violation per evaluation (a list of the dicts
    DesignProblem.evaluate and lsmbs.optimize return)."""
    ax = _axes(ax)
    k = np.arange(1, len(evaluations) + 1)
    ax.plot(k, [e["objective"] for e in evaluations], "o-", label="objective")
    ax.set_xlabel("evaluation")
    ax.set_ylabel("objective")
    ax2 = ax.twinx()
    ax2.plot(k, [e["max_violation"] for e in evaluations], "s--", color="tab:red",
             label="max. constraint violation")
    ax2.axhline(0, color="tab:red", lw=0.5)
    ax2.set_ylabel("max. relative constraint violation")
    ax.grid(True, alpha=0.3)
    return ax


def gradients(results, response, ax=None):
    """Bars of one scalar response's gradient by design variable, one bar group per method
    (`results`: {label: SensitivityResult})."""
    ax = _axes(ax)
    labels = list(results)
    variables = results[labels[0]].variables
    width = 0.8 / len(labels)
    x = np.arange(len(variables))
    for i, lab in enumerate(labels):
        g = np.asarray(results[lab].gradients[response])
        if g.ndim != 1:
            raise ValueError(f"'{response}' is a per-step response: plot one step's gradient, "
                             f"e.g. results[...].gradients['{response}'][k]")
        ax.bar(x + i * width, g, width, label=_text(lab))
    ax.set_xticks(x + 0.4 - width / 2, [_text(v) for v in variables])
    ax.set_ylabel(f"d {_text(response)} / d p")
    ax.axhline(0, color="k", lw=0.5)
    ax.legend()
    return ax
