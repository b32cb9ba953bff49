"""What an FMU's modelDescription.xml says about its linearization: the states (the
variables the `<Derivatives>` are derivatives of, in that order), their derivatives, the
real inputs and outputs, units, and the declared dependencies — the sparsity pattern of
[A B; C D] that lets structural zeros be skipped.

FMI 2.0 semantics (standard section 2.2.8): a `dependencies` attribute that is absent
means "depends on every known"; an empty one means "on none". An unknown that *is* a
state (the same value reference: an output that is a state, as in Reference-FMUs'
VanDerPol, issue #657, which declares `dependencies=""` for it) has the unit row e_j
whatever it declares.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .errors import NotLinearizableError


@dataclass(frozen=True)
class Var:
    """One real scalar variable of the FMU."""

    name: str
    vr: int
    unit: str | None = None
    start: float | None = None


@dataclass(frozen=True)
class Structure:
    """The linearization structure of one FMU interface (Co-Simulation or Model Exchange).

    `pattern` has one row per unknown (derivatives, then outputs) and one column per known
    (states, then inputs); True where the FMU declares a dependency. `identity[r] = j`
    when unknown r is state j itself (its row is the unit row e_j).
    """

    model_name: str
    interface: str
    states: list[Var]
    derivatives: list[Var]
    inputs: list[Var]
    outputs: list[Var]
    pattern: np.ndarray
    identity: dict[int, int] = field(default_factory=dict)
    provides_directional_derivative: bool = False

    @property
    def unknowns(self) -> list[Var]:
        """Derivatives, then outputs: the rows of [A B; C D]."""
        return self.derivatives + self.outputs

    @property
    def knowns(self) -> list[Var]:
        """States, then inputs: the columns of [A B; C D]."""
        return self.states + self.inputs


def _unit(v) -> str | None:
    if v.unit:
        return v.unit
    t = getattr(v, "declaredType", None)
    return getattr(t, "unit", None) or None


def _var(v) -> Var:
    start = None
    if v.start is not None:
        try:
            start = float(v.start)
        except (TypeError, ValueError):
            start = None
    return Var(v.name, v.valueReference, _unit(v), start)


def read_structure(md, interface: str) -> Structure:
    """The linearization structure of `md` (an fmpy ModelDescription) for `interface`
    ('CoSimulation' or 'ModelExchange').

    Raises NotLinearizableError when the FMU declares no `<Derivatives>` (its states are
    hidden, so A, B and C cannot be formed).
    """
    if md.fmiVersion != "2.0":
        raise NotLinearizableError(f"FMU '{md.modelName}': FMI {md.fmiVersion} is not supported (FMI 2.0 only)")
    info = md.coSimulation if interface == "CoSimulation" else md.modelExchange
    if not md.derivatives:
        raise NotLinearizableError(
            f"FMU '{md.modelName}' declares no <Derivatives> in its <ModelStructure>: its continuous states are "
            "not exposed, so A, B and C cannot be formed (export the FMU with its state derivatives listed)"
        )
    derivs = [u.variable for u in md.derivatives]
    for d in derivs:
        if d.derivative is None:
            raise NotLinearizableError(
                f"FMU '{md.modelName}': <Derivatives> lists '{d.name}' without a derivative attribute, "
                "so its state is unknown"
            )
    states = [d.derivative for d in derivs]
    inputs = [v for v in md.modelVariables if v.causality == "input" and v.type == "Real"]
    outputs = [u.variable for u in md.outputs if u.variable.type == "Real"]
    out_unknowns = [u for u in md.outputs if u.variable.type == "Real"]

    known_col = {v.valueReference: j for j, v in enumerate(states + inputs)}
    state_col = {v.valueReference: j for j, v in enumerate(states)}
    rows = list(md.derivatives) + out_unknowns
    pattern = np.zeros((len(rows), len(states) + len(inputs)), dtype=bool)
    identity: dict[int, int] = {}
    for r, u in enumerate(rows):
        vr = u.variable.valueReference
        if vr in state_col:
            identity[r] = state_col[vr]
            pattern[r, state_col[vr]] = True
            continue
        if u.dependencies is None:
            pattern[r, :] = True
        else:
            for dep in u.dependencies:
                j = known_col.get(dep.valueReference)
                if j is not None:
                    pattern[r, j] = True
    return Structure(
        model_name=md.modelName,
        interface=interface,
        states=[_var(v) for v in states],
        derivatives=[_var(v) for v in derivs],
        inputs=[_var(v) for v in inputs],
        outputs=[_var(v) for v in outputs],
        pattern=pattern,
        identity=identity,
        provides_directional_derivative=bool(info.providesDirectionalDerivative),
    )
