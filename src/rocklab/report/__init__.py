"""The documentation pages and the report's pages, written from the results of the workflow.

Every number quoted in ``docs/`` comes from the outputs of ``make run``: each
stage publishes its summary (:mod:`rocklab.summaries`), and
:mod:`rocklab.report.pages` gathers them into one numbers file (JSON) and
renders the Jinja2 page templates (``docs/templates``) with it, the tables of
:mod:`rocklab.report.tables` included, so a page cannot quote a number the
results do not hold. :mod:`rocklab.report.html` makes the result tables and
markdown reports browsable pages of ``snakemake --report``.
"""
