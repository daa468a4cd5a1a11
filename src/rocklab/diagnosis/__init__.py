"""Model diagnosis: what the literature model gets wrong, and why (Sect. 3, Figs. 14-15).

The paper does it once, by hand: Housner's e decays too slowly (Fig. 14a),
an experimentally calibrated e or the amplitude law of Eq. 17 fixes it
(Figs. 14b, 15b).  This package does it for any campaign, series by series;
the method and the catalogue of causes are in docs/diagnosis-method.md.

=================  ==============================================================
module             holds
=================  ==============================================================
``evidence``       the measured tests, their stacks, one-step residuals, covariates
``model``          the one wall model: parameters, what a law changes, impacts, free run
``causes/``        one module per candidate cause (parameters, signature, laws)
``catalogue``      the ordered list of causes, their laws, signatures and starts
``extended``       the model of named causes: arrays, exact simulator, errors
``estimation/``    the engine: noise model, fits, held-out deviance, bootstrap, selection
``discovery``      whether a finding's form was discovered (a family) rather than listed
``problem``        the tests of a series as a problem of the engine
``errors``         engineering errors of a model's free run, in words
``series``         diagnosis of a series
``pooling``        a boundary condition and a campaign from their series
``result``         the results as typed objects: diagnosis.json, limestone_diagnosis.json
``report``         results/diagnosis.json and diagnosis.md
``block_tests``    the same causes and engine on the limestone block tables
=================  ==============================================================
"""

from rocklab.diagnosis.catalogue import CAUSES, signatures
from rocklab.diagnosis.diagnosis_report import diagnosis_markdown, write_diagnosis
from rocklab.diagnosis.errors import engineering_rows, what_is_wrong
from rocklab.diagnosis.estimation import Problem, finite_mean, parameter_intervals, select_effects
from rocklab.diagnosis.evidence import (
    MeasuredTest,
    TestStack,
    measured_test,
    records_by_series,
    residuals,
    stored_records,
)
from rocklab.diagnosis.extended import engineering_errors, model_params, rocking_model, simulate_measured
from rocklab.diagnosis.pooling import diagnose_boundary, diagnose_campaign, with_boundaries
from rocklab.diagnosis.result import (
    BoundaryDiagnosis,
    CampaignDiagnosis,
    Finding,
    LimestoneDiagnosis,
    PooledFinding,
    SeriesDiagnosis,
    jsonable,
)
from rocklab.diagnosis.series import diagnose_records, diagnose_series
from rocklab.diagnosis.wall_model import free_run

__all__ = [
    "BoundaryDiagnosis",
    "CampaignDiagnosis",
    "Finding",
    "LimestoneDiagnosis",
    "PooledFinding",
    "SeriesDiagnosis",
    "CAUSES",
    "MeasuredTest",
    "Problem",
    "TestStack",
    "diagnose_boundary",
    "diagnose_campaign",
    "diagnose_records",
    "diagnose_series",
    "diagnosis_markdown",
    "engineering_errors",
    "engineering_rows",
    "finite_mean",
    "free_run",
    "jsonable",
    "measured_test",
    "model_params",
    "parameter_intervals",
    "records_by_series",
    "stored_records",
    "residuals",
    "rocking_model",
    "select_effects",
    "signatures",
    "simulate_measured",
    "what_is_wrong",
    "with_boundaries",
    "write_diagnosis",
]
