"""``--report DIR``: a Markdown report with figures of a diagnosis.

Figures (PNG, matplotlib Agg, written atomically): residual maps over the
pose (before/after), hysteresis loops of a few cycles, the candidates'
held-out errors against the noise floor, and per-axis before/after.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .. import _plotting as plots
from .._fileio import atomic_write_json, atomic_write_text
from .selection import ALPHA, Diagnosis


def residual_map(d: Diagnosis, path: Path) -> Path:
    plt = plots.figure()
    t = d.heldout_table
    x, y = t.tilt_rad * np.cos(t.azimuth_rad), t.tilt_rad * np.sin(t.azimuth_rad)
    before = 1e3 * np.linalg.norm(t.zeta_rad, axis=1)
    after = 1e3 * np.linalg.norm(d.selected_score.heldout_zeta_rad, axis=1)
    vmax = float(np.percentile(before, 98)) or 1.0
    fig, axes = plt.subplots(1, 2, figsize=(10, 4.2), sharex=True, sharey=True)
    for ax, val, title in ((axes[0], before, "nominal model (rig file)"),
                           (axes[1], after, f"selected: {d.selected}")):
        sc = ax.scatter(x, y, c=val, s=18, cmap="viridis", vmin=0, vmax=vmax)
        ax.set_title(f"{title}: RMS {np.sqrt(np.mean(val ** 2)):.2f} mrad", fontsize=9)
        ax.set_xlabel("tilt cos(azimuth) (rad)")
        ax.set_aspect("equal")
    axes[0].set_ylabel("tilt sin(azimuth) (rad)")
    fig.colorbar(sc, ax=axes, label="||log(R_pred^T R_meas)|| (mrad)")
    return plots.save(fig, path)


def hysteresis_loops(d: Diagnosis, path: Path, n_cycles: int = 4) -> Path:
    plt = plots.figure()
    t = d.heldout_table
    ids = list(dict.fromkeys(t.cycle.tolist()))[:n_cycles]
    fig, axes = plt.subplots(1, max(len(ids), 1), figsize=(3.2 * max(len(ids), 1), 3.4), squeeze=False)
    after = d.selected_score.heldout_zeta_rad
    for ax, c in zip(axes[0], ids):
        idx = np.flatnonzero(t.cycle == c)
        tau = t.rows.tau_meas_A_Nm[idx]
        direction = tau[np.argmax(np.linalg.norm(tau - tau[0], axis=1))] - tau[0]
        u = direction / (np.linalg.norm(direction) or 1.0)
        s = (tau - tau[0]) @ u
        # residual along the main axis of the before-residuals of this cycle
        zb = t.zeta_rad[idx]
        _, _, Vt = np.linalg.svd(zb - zb.mean(axis=0))
        v = Vt[0]
        ax.plot(s, 1e3 * zb @ v, "o-", label="nominal")
        ax.plot(s, 1e3 * after[idx] @ v, "s--", label=d.selected)
        ax.set_title(f"cycle {c}")
        ax.set_xlabel("load along cycle (N m)")
    axes[0][0].set_ylabel("residual along its main axis (mrad)")
    axes[0][0].legend(fontsize=8)
    fig.suptitle("hysteresis: loading and unloading branches (arrows of time follow the markers)")
    return plots.save(fig, path)


def candidate_errors(d: Diagnosis, path: Path) -> Path:
    plt = plots.figure()
    names = ["nominal", "nominal_refit"] + list(d.candidates)
    vals = [d.nominal_heldout_rms_rad, d.baseline.heldout_rms_rad] + [c.heldout_rms_rad for c in d.candidates.values()]
    colors = ["grey", "silver"] + ["tab:green" if n == d.selected else "tab:blue" for n in d.candidates]
    fig, ax = plt.subplots(figsize=(8, 3.6))
    ax.bar(range(len(names)), 1e3 * np.asarray(vals), color=colors)
    ax.axhline(1e3 * d.noise_floor_rad, color="k", ls=":", label=f"noise floor {1e3 * d.noise_floor_rad:.2f} mrad")
    ax.set_xticks(range(len(names)), names, rotation=30, ha="right")
    ax.set_ylabel("held-out RMS (mrad)")
    ax.legend()
    return plots.save(fig, path)


def before_after(d: Diagnosis, path: Path) -> Path:
    plt = plots.figure()
    zb, za = d.heldout_table.zeta_rad, d.selected_score.heldout_zeta_rad
    fig, axes = plt.subplots(1, 2, figsize=(9, 3.4))
    w = 0.38
    axes[0].bar(np.arange(3) - w / 2, 1e3 * np.sqrt(np.mean(zb ** 2, axis=0)), w, label="before")
    axes[0].bar(np.arange(3) + w / 2, 1e3 * np.sqrt(np.mean(za ** 2, axis=0)), w, label="after")
    axes[0].set_xticks(range(3), ["x", "y", "z"])
    axes[0].set_ylabel("RMS residual per axis of {A} (mrad)")
    axes[0].legend()
    bins = np.linspace(0, 1e3 * max(np.linalg.norm(zb, axis=1).max(), 1e-6), 30)
    axes[1].hist(1e3 * np.linalg.norm(zb, axis=1), bins, alpha=0.6, label="before")
    axes[1].hist(1e3 * np.linalg.norm(za, axis=1), bins, alpha=0.6, label="after")
    axes[1].set_xlabel("||residual|| (mrad)")
    axes[1].legend()
    return plots.save(fig, path)


def _fmt(x: float | None, scale: float = 1e3) -> str:
    return f"{scale * x:.3f}" if x is not None and np.isfinite(x) else "n/a"


def _g(x: float | None, spec: str = ".3g") -> str:
    return format(x, spec) if x is not None and np.isfinite(x) else "n/a"


def markdown(d: Diagnosis, j: dict, data_name: str) -> str:
    g = j["gap"]
    out = [f"# Sim-to-real gap diagnosis: {data_name}", "",
           f"**Selected effect: `{j['selected']}`**"
           + (f" (confounded with: {', '.join(j['confounded_with'])})" if j["confounded_with"] else ""), "",
           f"- held-out rows: {j['heldout']} ({j['rows']['test'] or j['rows']['train']} rows)",
           f"- gap before (nominal model, rig file): {_fmt(g['before_rad'])} mrad; after: {_fmt(g['after_rad'])} mrad",
           f"- noise floor: {_fmt(j['noise_floor_rad'])} mrad; systematic gap {_fmt(g['systematic_before_rad'])} "
           f"-> {_fmt(g['systematic_after_rad'])} mrad; fraction explained {_g(g['fraction_explained'], '.2f')} "
           f"(of which a recalibration of stiffness/pretension alone gives "
           f"{_g(g['fraction_explained_by_nominal_refit'], '.2f')})",
           f"- decision rule: {j['significance']['test']}; family-wise alpha = {ALPHA} "
           f"({j['significance']['per_candidate_alpha']:.4f} per candidate), held-out alpha = "
           f"{j['significance']['heldout_alpha']}",
           f"- second effect on top of the selected one: `{j['secondary']['effect']}`",
           f"- remaining signature after the selected model: "
           f"{'yes' if j['remaining_signature'].get('significant') else 'no'} "
           f"(p = {_g(j['remaining_signature'].get('p_value'))})", "",
           "## Candidates", "",
           "| effect | held-out RMS (mrad) | train RMS (mrad) | BIC | F-test p | held-out p | significant "
           "| rank / params | condition | fraction explained |", "|---|---|---|---|---|---|---|---|---|---|",
           f"| nominal (rig file) | {_fmt(j['baseline']['heldout_rms_rad'])} | {_fmt(j['baseline']['train_rms_rad'])} "
           "| | | | | 0 | | 0 |",
           f"| nominal_refit | {_fmt(j['nominal_refit']['heldout_rms_rad'])} | "
           f"{_fmt(j['nominal_refit']['train_rms_rad'])} | {_g(j['nominal_refit']['bic'], '.1f')} | | | | 2 | | "
           f"{_g(g['fraction_explained_by_nominal_refit'], '.2f')} |"]
    for c in j["candidates"]:
        if c.get("error"):
            out.append(f"| {c['effect']} | {c['error']} | | | | | no | | | |")
            continue
        out.append(f"| {c['effect']} | {_fmt(c['heldout_rms_rad'])} | {_fmt(c['train_rms_rad'])} "
                   f"| {_g(c['bic'], '.1f')} "
                   f"| {_g(c['p_value'], '.2g')} | {_g(c['heldout_p_value'], '.2g')} "
                   f"| {'yes' if c['significant'] else 'no'} "
                   f"| {c['rank']} / {c['n_params']} | {_g(c['condition'])} | {_g(c['fraction_explained'], '.2f')} |")
    sel = next((c for c in j["candidates"] if c["effect"] == j["selected"]), None)
    if sel is not None:
        out += ["", f"## Fitted parameters of `{sel['effect']}` (+- 1 standard error)", "",
                "| parameter | value | sd |", "|---|---|---|"]
        out += [f"| {k} | {_g(v, '.4g')} | {_g(sel['param_sd'][k], '.2g')} |" for k, v in sel["params"].items()]
        out += [f"| {k} (nuisance) | {_g(v, '.4g')} | |" for k, v in sel["nuisance"].items()]
        if sel["derived"]:
            out += ["", "Derived: `" + str(sel["derived"]) + "`"]
        if not sel["identifiable"]:
            out += ["", f"Note: the augmented fit is ill-conditioned (condition {_g(sel['condition'])}, rank "
                        f"{sel['rank']} of {sel['n_params']}); some parameter combinations are not determined "
                        "by these data (hole_offsets: a weak prior keeps them near zero)."]
    loc = j["localisation"]
    out += ["", "## Where the gap lies (held-out rows)", "",
            "| breakdown | group | rows | before (mrad) | after (mrad) |",
            "|---|---|---|---|---|"]
    for key in ("by_tilt", "by_azimuth", "by_load_magnitude", "by_load_direction", "by_branch"):
        for grp in loc[key]:
            out.append(f"| {key[3:]} | {grp['group']} | {grp['rows']} | {_fmt(grp['rms_before_rad'])} | "
                       f"{_fmt(grp['rms_after_rad'])} |")
    for a, v in loc["by_axis"].items():
        out.append(f"| axis | {a} | | {_fmt(v['rms_before_rad'])} | {_fmt(v['rms_after_rad'])} |")
    hb, ha = loc["hysteresis_before"], loc["hysteresis_after"]
    if hb.get("pairs"):
        out += ["", f"Hysteresis (loading minus unloading at matched loads, {hb['pairs']} pairs): "
                    f"{_fmt(hb['rms_up_minus_down_rad'])} mrad before (noise alone: "
                    f"{_fmt(hb['expected_from_noise_rad'])}; p = {_g(hb['p_value'], '.2g')}), "
                    f"{_fmt(ha['rms_up_minus_down_rad'])} mrad after."]
    out += ["", "## Figures", "", "![residual map](residual_map.png)", "", "![hysteresis](hysteresis.png)", "",
            "![candidates](candidates.png)", "", "![before/after](before_after.png)", "",
            "Full numbers: `diagnosis.json`."]
    return "\n".join(out) + "\n"


def write_report(d: Diagnosis, out_dir: str | Path, data_name: str = "log") -> Path:
    """Write ``index.md``, ``diagnosis.json`` and four figures into ``out_dir``; returns index.md."""
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    j = d.as_json()
    residual_map(d, out_dir / "residual_map.png")
    hysteresis_loops(d, out_dir / "hysteresis.png")
    candidate_errors(d, out_dir / "candidates.png")
    before_after(d, out_dir / "before_after.png")
    atomic_write_json(out_dir / "diagnosis.json", j)
    return atomic_write_text(out_dir / "index.md", markdown(d, j, data_name))
