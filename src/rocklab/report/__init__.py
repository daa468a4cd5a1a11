"""The documentation pages, written from the results of the workflow.

Every number quoted in ``docs/`` comes from the outputs of ``make run``:
:mod:`rocklab.report.numbers` reads them into one numbers file (JSON), and
:mod:`rocklab.report.pages` fills the page templates (``docs/templates``)
with it, so a page cannot quote a number the results do not hold.
:mod:`rocklab.report.html` makes the result tables and markdown reports
browsable pages of ``snakemake --report``.
"""
