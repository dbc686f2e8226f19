"""Report section 'Figure index': which generated file shows each figure of the two papers
(Ugalde-Loo et al. Figs. 4, 6-8; Amezquita-Brooks et al. Figs. 3-9, 15, 17-22), in the order of
``acdrive._report.icad_targets.FIGURES``.
"""

from __future__ import annotations

from acdrive._report import icad_targets as targets

#: Which generated file shows each figure of the papers (``icad_targets.FIGURES``).
FIGURE_FILES = {
    (targets.UGALDE, "Fig. 4"): "s001_pmsg_nyquist.png",
    (targets.UGALDE, "Fig. 6"): "s001_im_poles.png",
    (targets.UGALDE, "Fig. 7"): "s001_im_poles.png",
    (targets.UGALDE, "Fig. 8"): "s001_im_nyquist.png",
    (targets.AMEZQUITA, "Fig. 3"): "s002_nyquist_gamma.png",
    (targets.AMEZQUITA, "Fig. 4"): "s002_design_models.png",
    (targets.AMEZQUITA, "Fig. 5"): "s002_bode_channels.png",
    (targets.AMEZQUITA, "Fig. 6"): "s002_bode_kg.png",
    (targets.AMEZQUITA, "Fig. 7"): "s002_nyquist_gamma_h.png",
    (targets.AMEZQUITA, "Fig. 8"): "s002_coupling.png",
    (targets.AMEZQUITA, "Fig. 9"): "s002_perturbed_nyquist.png",
    (targets.AMEZQUITA, "Fig. 15"): "s002_pi_vs_20.png",
    (targets.AMEZQUITA, "Fig. 17"): "s002_pi_family.png",
    (targets.AMEZQUITA, "Fig. 19"): "s002_pi_vs_20.png",
    (targets.AMEZQUITA, "Fig. 21"): "s002_perturbed_nyquist.png",
    (targets.AMEZQUITA, "Fig. 22"): "s002_perturbed_bode.png",
}


def figure_index(fig_rel: str) -> str:
    """The figure-index section as Markdown, files linked from the folder ``fig_rel``."""
    lines = [
        "## Figure index",
        "",
        "| paper | figure | shows | acdrive file |",
        "|---|---|---|---|",
    ]
    for (paper, fig), what in targets.FIGURES.items():
        name = FIGURE_FILES[(paper, fig)]
        lines.append(f"| {paper} | {fig} | {what} | [{name}]({fig_rel}/{name}) |")
    lines.append(
        f"| {targets.AMEZQUITA} | Figs. 18, 20 | step responses (linear, w_r = 375) | "
        f"[s002_steps.png]({fig_rel}/s002_steps.png) |"
    )
    return "\n".join(lines) + "\n"
