# Stage 7: the documentation pages of docs/, every number read from the
# results (rocklab.report). `make docs` runs this rule and copies its
# outputs into docs/; tests/test_docs.py checks the committed pages.

#: One page per template; a new template is a new page.
DOC_PAGES = sorted(p.name for p in Path(workflow.basedir, "docs", "templates").glob("*.md"))


DOCS_OUTPUTS = [res("docs", "numbers.json")] + [res("docs", page) for page in DOC_PAGES]


rule docs:
    input:
        # Every stage has run, so every job's benchmark file exists.
        results=all_outputs(),
        tables=[rules.dissipation_tables.output[name] for name in ("tests", "laws", "effects")],
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
    script:
        "../../scripts/docs_pages.py"
