# Stage 7: the documentation pages of docs/, every number read from the
# results (rocklab.report). `make docs` runs this rule and copies its
# outputs into docs/; tests/test_docs.py checks the committed pages.

#: One page per template; a new template is a new page.
DOC_TEMPLATES = Path(workflow.basedir, "docs", "templates")
DOC_PAGES = sorted(p.name for p in DOC_TEMPLATES.glob("*.md"))


def docs_outputs():
    return [res("docs", "numbers.json")] + [res("docs", page) for page in DOC_PAGES]


rule docs:
    input:
        # Every stage has run, so every job's benchmark file exists.
        results=all_outputs(),
        tables=[res(name) for name in ("tests.csv", "amplitude_laws.csv", "effects.csv")],
        templates=[str(DOC_TEMPLATES / page) for page in DOC_PAGES],
    output:
        numbers=res("docs", "numbers.json"),
        pages=[res("docs", page) for page in DOC_PAGES],
    log:
        res("logs", "docs.log"),
    run:
        from rocklab.report.pages import write_docs

        written = write_docs(RESULTS, DOC_TEMPLATES, Path(output.numbers).parent)
        Path(log[0]).write_text("".join(f"wrote {p}\n" for p in written))
