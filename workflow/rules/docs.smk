# Stage 7: the documentation pages of docs/, every number read from the
# results (rocklab.report). `make docs` runs this rule and copies its
# outputs into docs/; tests/test_docs.py checks the committed pages.

#: One page per template; a new template is a new page.
DOC_PAGES = sorted(p.name for p in Path(workflow.basedir, "docs", "templates").glob("*.md"))


def docs_outputs():
    return [res("docs", "numbers.json")] + [res("docs", page) for page in DOC_PAGES]


rule docs:
    input:
        # Every stage has run, so every job's benchmark file exists.
        results=all_outputs(),
        tables=[res(name) for name in ("tests.csv", "amplitude_laws.csv", "effects.csv")],
        templates=[repo_path("docs", "templates", page) for page in DOC_PAGES],
    output:
        numbers=res("docs", "numbers.json"),
        pages=[res("docs", page) for page in DOC_PAGES],
    params:
        results_dir=config["results_dir"],
    log:
        res("logs", "docs.log"),
    benchmark:
        res("benchmarks", "docs.tsv")
    script:
        "../../scripts/docs_pages.py"
