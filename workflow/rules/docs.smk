# Stage 7: the documentation pages of docs/, every number from the summaries
# that the stages publish (results/summaries, rocklab.summaries) and the job
# times. `make docs` runs this rule and copies its outputs into docs/;
# tests/test_docs.py checks the committed pages.

#: One page per template; a new template is a new page.
DOC_PAGES = sorted(p.name for p in Path(workflow.basedir, "docs", "templates").glob("*.md"))


DOCS_OUTPUTS = [res("docs", "numbers.json")] + [res("docs", page) for page in DOC_PAGES]


rule docs:
    input:
        # Every stage has run, so every job's benchmark file exists.
        results=all_outputs(),
        summaries=[
            rules.qc_table.output.docs_summary,
            rules.dissipation_tables.output.docs_summary,
            rules.diagnosis.output.docs_summary,
            rules.campaign_effects.output.docs_summary,
            rules.limestone_diagnosis.output.docs_summary,
            rules.map_summary.output.docs_summary,
            rules.calibrated_map_changes.output.docs_summary,
            rules.instrument_accuracy.output.docs_summary,
        ],
        templates=[repo_path("docs", "templates", page) for page in DOC_PAGES],
    output:
        numbers=res("docs", "numbers.json"),
        pages=[res("docs", page) for page in DOC_PAGES],
    log:
        res("logs", "docs.log"),
    benchmark:
        res("benchmarks", "docs.tsv")
    params:
        results_dir=lambda wildcards, output: str(Path(output.numbers).parents[1]),
        # the checkout (of the templates, docs/templates/): its SLURM profile,
        # configuration and embedded campaign make the cluster projection
        checkout=lambda wildcards, input: str(Path(input.templates[0]).parents[2]),
    script:
        "../../scripts/docs_pages.py"
