"""Snakemake shim: indices of every map (Fig. 22), reductions between models, record-by-record comparison."""

from rocklab import jobs
from rocklab.io import load_datasets, write_table
from rocklab.seismic.accelerograms import table4_agreement
from rocklab.seismic.indices import summary_table
from rocklab.seismic.maps_summary import maps_summary
from rocklab.seismic.paper_comparison import TABLE4_SUBSET, record_comparison, reductions
from rocklab.summaries import write_summary

job = jobs.start(snakemake)
summary = summary_table(load_datasets(snakemake.params.maps))
agreement = table4_agreement()
matching = agreement.index[agreement.pga_pgv_match]
write_table(summary, snakemake.output.summary, snakemake.params.summary_schema)
write_table(
    reductions(summary, subsets={TABLE4_SUBSET: matching}),
    snakemake.output.reductions,
    snakemake.params.reductions_schema,
)
write_table(record_comparison(summary, agreement), snakemake.output.comparison, snakemake.params.comparison_schema)
out = snakemake.output
write_summary(maps_summary(out.summary, out.reductions, out.comparison), out.docs_summary)
job.finish()
