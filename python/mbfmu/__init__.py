"""mbfmu: A, B, C, D of FMI 2.0 FMUs at checkpoints — mbfmu's exact multibody FMUs and any
other FMU — with eigenvalue tables, python-control systems, files, parameter sweeps and
the linearization of coupled systems of FMUs (SSP).

    import mbfmu
    lins = mbfmu.linearize("bicycle.fmu", at=[0, 1, 2])
    print(lins[0])                    # eigenvalue table
    sys = lins[0].to_control()        # control.StateSpace with names
    low = mbfmu.eigenvalues("chain.xml", modes=10)   # the 10 lowest, without forming A
"""

from .errors import ArgumentError, FMUCallError, FMUNotFoundError, MbfmuError, NotLinearizableError
from .files import load, save
from .linearization import EigenRow, Linearization
from .linearize_fmu import DifferencesWarning, linearize
from .pack import PackWarning, pack
from .spectrum import Spectrum, eigenvalues
from .sweep import Sweep, sweep
from .system import linearize_system

__all__ = [
    "ArgumentError",
    "DifferencesWarning",
    "EigenRow",
    "FMUCallError",
    "FMUNotFoundError",
    "Linearization",
    "MbfmuError",
    "NotLinearizableError",
    "PackWarning",
    "Spectrum",
    "Sweep",
    "eigenvalues",
    "linearize",
    "linearize_system",
    "load",
    "pack",
    "save",
    "sweep",
]
