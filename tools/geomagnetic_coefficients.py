"""Write ``rigid_rot_sim/core/geomagnetic_coefficients.py`` from the published coefficient files.

The core reads no files, so the Gauss coefficients of the field models live in a Python module, the numbers of
the published files in file order, as decimal text (parsed to the same doubles as the files). Sources:

* ``IGRF14.shc``: the 14th-generation International Geomagnetic Reference Field (IAGA Working Group V-MOD,
  doi:10.5281/zenodo.14012302), as shipped by ``ppigrf`` 2.1.0 on PyPI (MIT); 27 epochs 1900.0-2030.0 (2030.0
  is 2025.0 plus five years of the predictive secular variation), degree 13 (10 before 2000.0).
* ``WMM.COF``: the World Magnetic Model 2025 (NOAA NCEI and BGS, public domain), as shipped by ``pygeomag``
  1.1.0 on PyPI (MIT) as ``pygeomag/wmm/WMM.COF``; epoch 2025.0, degree 12, with its secular variation.

Usage::

    python tools/geomagnetic_coefficients.py IGRF14.shc WMM.COF > rigid_rot_sim/core/geomagnetic_coefficients.py
"""

from __future__ import annotations

import hashlib
import sys
import textwrap
from pathlib import Path

WIDTH = 110


def _numbers(rows: list[list[str]]) -> str:
    text = " ".join(" ".join(row) for row in rows)
    return "\n".join(textwrap.wrap(text, WIDTH))


def igrf_rows(path: Path) -> tuple[str, list[list[str]]]:
    """(the epochs line, the rows ``n m value*K``) of an ``.shc`` file."""
    lines = [line.split() for line in path.read_text().splitlines() if line.strip() and not line.startswith("#")]
    return " ".join(lines[1]), lines[2:]


def wmm_rows(path: Path) -> tuple[str, list[list[str]]]:
    """(the header line, the rows ``n m g h gdot hdot``) of a ``WMM.COF`` file."""
    lines = [line.split() for line in path.read_text().splitlines() if line.strip()]
    rows = [row for row in lines[1:] if not row[0].startswith("9999")]
    return " ".join(lines[0]), rows


def module(igrf: Path, wmm: Path) -> str:
    epochs, igrf_data = igrf_rows(igrf)
    header, wmm_data = wmm_rows(wmm)
    digest = {p.name: hashlib.sha256(p.read_bytes()).hexdigest() for p in (igrf, wmm)}
    return f'''"""Gauss coefficients (nT, nT/yr) of IGRF-14 and WMM2025 (``tools/geomagnetic_coefficients.py``).

Do not edit: regenerate. Provenance (the tool's docstring says where each file comes from):

* ``IGRF14.shc`` (IAGA, doi:10.5281/zenodo.14012302; from ``ppigrf`` 2.1.0),
  sha256 {digest[igrf.name]};
* ``WMM.COF`` (NOAA NCEI / BGS WMM2025, public domain; from ``pygeomag`` 1.1.0),
  sha256 {digest[wmm.name]}.

:data:`IGRF14_EPOCHS` are the file's epochs (decimal years); :data:`IGRF14_ROWS` its rows ``n m value*K`` in file
order (``m < 0`` is the ``h`` of order ``|m|``). :data:`WMM2025_HEADER` is the file's first line;
:data:`WMM2025_ROWS` its rows ``n m g h g_dot h_dot``.
"""

IGRF14_EPOCHS = """
{_numbers([epochs.split()])}
"""

IGRF14_ROWS = """
{_numbers(igrf_data)}
"""

WMM2025_HEADER = "{header}"

WMM2025_ROWS = """
{_numbers(wmm_data)}
"""
'''


if __name__ == "__main__":
    sys.stdout.write(module(Path(sys.argv[1]), Path(sys.argv[2])))
