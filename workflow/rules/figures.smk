# Stage: figures of Sect. 2 (Figs. 6, 8, 9) from one reduced test and of
# Sects. 3-4 (Figs. 10, 11, 13, 16-20) from the dissipation tables, with
# their captions for `snakemake --report`.  Each figure rule depends on the
# test it draws only, chosen from the QC table or tests.csv once their
# checkpoint has run, or named in the config.

FIG_SPECIMEN = config["figures"]["fig9_specimen"]
#: Test of Figs. 6, 8 and 9; empty: the first valid test.
KINEMATICS_SAMPLE = config["figures"]["sample_test"]
#: Test of Fig. 20a; empty: rocklab.plots.dissipation.fig20_sample of tests.csv.
FIG20_SAMPLE = config["figures"]["fig20_test"]
DISSIPATION_FIGS = ("10", "11", "13", "16", "17", "18", "19", "20")


report: "../report/workflow.rst"


FIGURE_OUTPUTS = [res("figures", f"fig{n}.png") for n in ("06", "08", "09", *DISSIPATION_FIGS)]


rule kinematics_figures:
    input:
        qc=rules.qc_table.output.qc,
        kinematics=rules.qc_table.output.kinematics,
        # the folder of the sample test's reduction job; the test's file is a param
        sample=lambda wildcards: reduced_inputs([kinematics_sample(wildcards)]),
    output:
        fig6=report_figure("06", "kinematics", "a record, elongation and velocity"),
        fig8=report_figure("08", "kinematics", "the four degrees of freedom"),
        fig9=report_figure("09", "kinematics", "Eq. 3 against Eq. 8; peaks"),
    log:
        res("logs", "kinematics_figures.log"),
    benchmark:
        res("benchmarks", "kinematics_figures.tsv")
    params:
        specimen=FIG_SPECIMEN,
        sample=lambda wildcards: test_file(kinematics_sample(wildcards)),
    script:
        "../../scripts/kinematics_figures.py"


rule dissipation_figures:
    input:
        tests=rules.dissipation_tables.output.tests,
        e_by_n=rules.dissipation_tables.output.e_by_n,
        series=rules.dissipation_tables.output.series,
        sample=lambda wildcards: reduced_inputs(fig20_sample_test(wildcards)),
    output:
        fig10=report_figure("10", "dissipation", "theta0 / alpha test by test", "Figures"),
        fig11=report_figure("11", "dissipation", "e_exp / e_an after n impacts", "Figures"),
        fig13=report_figure("13", "dissipation", "e_exp / e_an per series", "Figures"),
        fig16=report_figure("16", "dissipation", "theta0 / alpha per series", "Figures"),
        fig17=report_figure("17", "dissipation", "p T_1/4 per series", "Figures"),
        fig18=report_figure("18", "dissipation", "cycles per series", "Figures"),
        fig19=report_figure("19", "dissipation", "duration p D per series", "Figures"),
        fig20=report_figure("20", "dissipation", "channel-5 amplification", "Figures"),
    log:
        res("logs", "dissipation_figures.log"),
    benchmark:
        res("benchmarks", "dissipation_figures.tsv")
    params:
        sample=lambda wildcards: [test_file(t) for t in fig20_sample_test(wildcards)],
    script:
        "../../scripts/dissipation_figures.py"
