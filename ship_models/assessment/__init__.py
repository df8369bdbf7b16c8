"""IMO second-generation intact stability criteria for surf-riding/broaching.

Level 1 and Level 2 of the surf-riding/broaching criterion of the Interim Guidelines
MSC.1/Circ.1627 (2020; Explanatory Notes MSC.1/Circ.1652, 2023; the criterion's own
text could not be checked, see :mod:`~ship_models.assessment.standard`), on the
vessels of broachkit, and beyond the standard: Level 2 with the exact surf-riding
threshold of the same surge equation and the operational limit ``Fn``. Modules:

* :mod:`~ship_models.assessment.standard`: the criterion's numbers (data file with
  sources) and the user's scatter table;
* :mod:`~ship_models.assessment.wave_weights`: the weights ``w_ij``
  (Longuet-Higgins 1983);
* :mod:`~ship_models.assessment.melnikov`: Melnikov's ``Fn_cr``;
* :mod:`~ship_models.assessment.exact`: the exact ``Fn_cr`` by continuation of a
  connecting orbit over the wave cases;
* :mod:`~ship_models.assessment.exact_sweep`: the same as tasks of the sweep engine
  (local processes, Dask);
* :mod:`~ship_models.assessment.criteria`: Level 1, ``C``, the operational limit;
* :mod:`~ship_models.assessment.assess`: all of it for one vessel;
* :mod:`~ship_models.assessment.figures`: the report's figures.
"""

from .assess import Assessment, assess
from .criteria import Level1Result, Level2Result, level1, level2, operational_limit
from .exact import ExactGrid, exact_threshold_grid, surf_riding_connection
from .exact_sweep import exact_threshold_sweep
from .melnikov import MelnikovGrid, melnikov_grid, pendulum_melnikov
from .standard import ScatterTable, SurfRidingStandard, load_standard, read_scatter_table
from .wave_weights import band_probability, wave_case_weights

__all__ = [
    "Assessment",
    "ExactGrid",
    "Level1Result",
    "Level2Result",
    "MelnikovGrid",
    "ScatterTable",
    "SurfRidingStandard",
    "assess",
    "band_probability",
    "exact_threshold_grid",
    "exact_threshold_sweep",
    "level1",
    "level2",
    "load_standard",
    "melnikov_grid",
    "operational_limit",
    "pendulum_melnikov",
    "read_scatter_table",
    "surf_riding_connection",
    "wave_case_weights",
]
