# Stage: figures of Sect. 2 (Figs. 6, 8, 9) from the reduced tests and of
# Sects. 3-4 (Figs. 10, 11, 13, 16-20) from the dissipation tables, with
# their captions for `snakemake --report`.

FIG_SPECIMEN = config["figures"]["fig9_specimen"]
DISSIPATION_FIGS = ("10", "11", "13", "16", "17", "18", "19", "20")


report: "../report/workflow.rst"


def report_figure(n, category):
    """A figure output, shown in the report with workflow/report/figNN.rst."""
    return report(res("figures", f"fig{n}.png"), caption=f"../report/fig{n}.rst",
                  category=category)


def figure_outputs():
    return [res("figures", f"fig{n}.png") for n in ("06", "08", "09", *DISSIPATION_FIGS)]


rule kinematics_figures:
    input:
        qc=res("qc.csv"),
        kinematics=res("kinematics.csv"),
        tests=expand(res("tests", "{test_id}.nc"), test_id=TEST_IDS),
    output:
        fig6=report_figure("06", "Kinematics (Sect. 2)"),
        fig8=report_figure("08", "Kinematics (Sect. 2)"),
        fig9=report_figure("09", "Kinematics (Sect. 2)"),
    params:
        sample_test=config["figures"]["sample_test"],
        specimen=FIG_SPECIMEN,
    log:
        res("logs", "kinematics_figures.log"),
    benchmark:
        res("benchmarks", "kinematics_figures.tsv")
    script:
        "../../scripts/kinematics_figures.py"


rule dissipation_figures:
    input:
        tests=res("tests.csv"),
        e_by_n=res("e_by_n.csv"),
        series=res("series.csv"),
        tests_nc=expand(res("tests", "{test_id}.nc"), test_id=TEST_IDS),
    output:
        fig10=report_figure("10", "Energy dissipation (Sects. 3-4)"),
        fig11=report_figure("11", "Energy dissipation (Sects. 3-4)"),
        fig13=report_figure("13", "Energy dissipation (Sects. 3-4)"),
        fig16=report_figure("16", "Energy dissipation (Sects. 3-4)"),
        fig17=report_figure("17", "Energy dissipation (Sects. 3-4)"),
        fig18=report_figure("18", "Energy dissipation (Sects. 3-4)"),
        fig19=report_figure("19", "Energy dissipation (Sects. 3-4)"),
        fig20=report_figure("20", "Energy dissipation (Sects. 3-4)"),
    params:
        sample_test=config["figures"]["fig20_test"],
    log:
        res("logs", "dissipation_figures.log"),
    benchmark:
        res("benchmarks", "dissipation_figures.tsv")
    script:
        "../../scripts/dissipation_figures.py"
