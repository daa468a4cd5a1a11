"""Snakemake shim: Figs. 14-15 of each series' sample test, and of the largest series of each boundary."""

from pathlib import Path

from rocklab import jobs
from rocklab.diagnosis import CampaignDiagnosis
from rocklab.disk import write_bytes
from rocklab.plots import save_png
from rocklab.plots.diagnosis import series_figures

job = jobs.start(snakemake)
diagnosis = CampaignDiagnosis.from_json(snakemake.input.diagnosis)
out = Path(snakemake.output.series)
out.mkdir(parents=True, exist_ok=True)
written = {}  # figure -> its file: Figs. 14-15 are series' figures, copied, not drawn again
for name, fig in series_figures(diagnosis, snakemake.params.tests).items():
    path = Path(snakemake.output[name]) if name in ("fig14", "fig15") else out / f"{name}.png"
    path.parent.mkdir(parents=True, exist_ok=True)  # discovered/<series>: the forms found beyond the catalogue
    if fig in written:
        write_bytes(path, written[fig].read_bytes())
    else:
        save_png(fig, path, dpi=110)
        written[fig] = path
job.finish()
