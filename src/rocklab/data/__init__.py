"""Data shipped with rocklab (package data), each folder with its provenance.

``accelerograms/``
    The recorded ground motions of Table 4, with ``manifest.csv`` and
    ``README.md`` (sources, stand-ins, differences from Table 4); read by
    :mod:`rocklab.seismic.accelerograms` (:func:`~rocklab.seismic.accelerograms.load_record`).
``uminho-limestone-free-rocking/``
    Per-trial and per-impact tables of the UMinho limestone blocks
    (Colombo et al., CC BY 4.0: cite DOI 10.60756/uminho-jh25), with
    ``README.md`` and ``SOURCE.md`` (provenance, checks); read by
    :mod:`rocklab.diagnosis.block_tests` (:func:`~rocklab.diagnosis.block_tests.read_events`).
``paper_claims.csv``
    The paper's campaign-wide statements (Sects. 2-4, Figs. 10 and 13,
    Tables 2-3) that the campaign tests, each with where the paper says it;
    read by :mod:`rocklab.dissipation.covariates`
    (:func:`~rocklab.dissipation.claims.read_claims`).
``claim_margins.csv``
    The equivalence margin of every parameter of the diagnosis catalogue in
    each boundary condition: the smallest change that changes the reference
    wall's simulated free-rocking duration by 5 %; written by
    ``python -m rocklab.dissipation.claims``
    (:func:`~rocklab.dissipation.claims.margin_table`), read by
    :func:`~rocklab.dissipation.claims.margin_of`.

The files are found through :mod:`importlib.resources`, so they are where the
package is: the checkout's ``src/rocklab/data/`` or an installed
``site-packages/rocklab/data/``.
"""

from __future__ import annotations

from importlib import resources
from pathlib import Path


def data_path(*parts) -> Path:
    """Path of a file or folder shipped in :mod:`rocklab.data`.

    Parameters
    ----------
    *parts : str
        Path components below ``rocklab/data/``, e.g. ``"accelerograms"``.

    Returns
    -------
    Path
        A file-system path: the readers (obspy, pandas) take paths.

    Raises
    ------
    RuntimeError
        When rocklab is imported from a zip archive, whose members have no
        file-system path (``pip install`` always installs a folder).
    """
    root = resources.files(__name__)
    if not isinstance(root, Path):
        raise RuntimeError(f"rocklab's data need rocklab installed as a folder, not imported from {root}")
    return root.joinpath(*parts)


#: Folder of the UMinho limestone blocks' tables, with their provenance.
LIMESTONE = data_path("uminho-limestone-free-rocking")
