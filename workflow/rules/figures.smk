# Stage: figures of Sect. 2 (Figs. 6, 8, 9) from the reduced tests.

FIG_SPECIMEN = config.get("figures", {}).get("fig9_specimen", "5a")


def figure_outputs():
    return [res("figures", f"fig{n}.png") for n in ("06", "08", "09")]


rule kinematics_figures:
    input:
        qc=res("qc.csv"),
        kinematics=res("kinematics.csv"),
        tests=expand(res("tests", "{test_id}.nc"), test_id=TEST_IDS),
    output:
        fig6=res("figures", "fig06.png"),
        fig8=res("figures", "fig08.png"),
        fig9=res("figures", "fig09.png"),
    params:
        sample_test=config.get("figures", {}).get("sample_test", ""),
        specimen=FIG_SPECIMEN,
    log:
        res("logs", "kinematics_figures.log"),
    benchmark:
        res("benchmarks", "kinematics_figures.tsv")
    script:
        "../../scripts/kinematics_figures.py"
