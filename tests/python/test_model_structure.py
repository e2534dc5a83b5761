"""ModelStructure as importers read it: each output's declared direct dependencies are
exactly the inputs that change it within one instant (no false algebraic loops when a
specimen FMU closes the loop through external_force), and the rest of the description
tools rely on: structured names, enumerations, bounds, display units, header, icon."""
import zipfile

import numpy as np
from fmpy import extract, read_model_description
from fmpy.fmi2 import FMU2Slave

INPUTS = ["ref_displacement", "ref_velocity", "ref_acceleration", "external_force"]
# a change of one input by this much moves a directly dependent output far above rounding
# (the smallest such effect, Kdp-free Ka r'' on the command, is 1e-4 of it)
PERTURBATION = {"ref_displacement": 1e-3, "ref_velocity": 1e-2, "ref_acceleration": 1.0,
                "external_force": 1e4}


def observed_feedthrough(fmu_path, params):
    """{output: set of inputs} that change the output at one instant, after 0.5 s of a
    2 Hz sine put the table in motion (perturb, read, restore; no step taken)."""
    md = read_model_description(fmu_path)
    vr = {v.name: v.valueReference for v in md.modelVariables}
    outputs = [v.name for v in md.modelVariables if v.causality == "output"]
    slave = FMU2Slave(guid=md.guid, unzipDirectory=extract(fmu_path),
                      modelIdentifier=md.coSimulation.modelIdentifier, instanceName="deps")
    slave.instantiate()
    slave.setupExperiment(startTime=0.0)
    slave.enterInitializationMode()
    for k, x in params.items():
        slave.setReal([vr[k]], [x])
    slave.exitInitializationMode()
    h, w, t = 1 / 512, 2 * np.pi * 2, 0.0
    ins = [vr[n] for n in INPUTS]
    u = []
    for _ in range(256):
        u = [0.01 * np.sin(w * t), 0.01 * w * np.cos(w * t), -0.01 * w * w * np.sin(w * t), 2e3]
        slave.setReal(ins, u)
        slave.doStep(t, h)
        t += h
    outs = [vr[o] for o in outputs]
    base = slave.getReal(outs)
    found = {o: set() for o in outputs}
    for i, name in enumerate(INPUTS):
        bumped = list(u)
        bumped[i] += PERTURBATION[name]
        slave.setReal(ins, bumped)
        moved = slave.getReal(outs)
        slave.setReal(ins, u)
        assert slave.getReal(outs) == base, "restoring the inputs must restore the outputs"
        for o, a, b in zip(outputs, base, moved):
            if a != b:
                found[o].add(name)
    slave.terminate()
    slave.freeInstance()
    return found


def declared_feedthrough(fmu_path):
    """{output: inputs it declares}; the other knowns listed are the states (Model
    Exchange), which no input perturbation touches."""
    md = read_model_description(fmu_path)
    return {u.variable.name: {d.name for d in (u.dependencies or []) if d.causality == "input"}
            for u in md.outputs}


def test_declared_dependencies_are_exactly_the_direct_feedthrough(fmu_path):
    declared = declared_feedthrough(fmu_path)
    assert declared["acceleration"] == {"external_force"}
    # with acceleration feedback on, every declared dependency shows, and nothing else
    with_ka = observed_feedthrough(fmu_path, {"controller.ka": 2e-3})
    assert with_ka == declared, (with_ka, declared)
    # with the defaults (Ka = Fa = 0) the command reads neither the force nor r'': still
    # no input moves an output that declares no dependency on it
    defaults = observed_feedthrough(fmu_path, {})
    for o, ins in defaults.items():
        assert ins <= declared[o], (o, ins)
    assert defaults["valve_command"] == {"ref_displacement", "ref_velocity"}
    md = read_model_description(fmu_path)
    acceleration = next(u for u in md.outputs if u.variable.name == "acceleration")
    kinds = dict(zip((d.name for d in acceleration.dependencies), acceleration.dependenciesKind))
    assert kinds["external_force"] == "fixed"
    # every other known an output lists is a continuous state
    for u in md.outputs:
        for d in u.dependencies:
            assert d.causality == "input" or d.name.startswith("state."), (u.variable.name, d.name)


def test_description_carries_what_tools_read(fmu_path):
    md = read_model_description(fmu_path)
    assert md.variableNamingConvention == "structured"
    for attr in ("author", "version", "copyright", "license", "generationDateAndTime"):
        assert getattr(md, attr), attr
    by_name = {v.name: v for v in md.modelVariables}
    sv = by_name["servovalve.model"]
    assert sv.type == "Enumeration"
    items = {i.name: int(i.value) for i in sv.declaredType.items}
    assert items == {"delay": 1, "first_order": 2, "second_order": 3}
    for v in md.modelVariables:
        if v.causality == "parameter" and v.type == "Real":
            assert v.min is not None, v.name
            lo, hi = float(v.min), float(v.max) if v.max is not None else np.inf
            assert lo <= float(v.start) <= hi, v.name
    assert by_name["displacement"].displayUnit == "mm"
    assert by_name["acceleration"].displayUnit == "g"
    assert by_name["pressure_a"].displayUnit == "bar"
    with zipfile.ZipFile(fmu_path) as z:
        assert z.read("model.png")[:8] == b"\x89PNG\r\n\x1a\n"
        assert "resources/parameters.toml" in z.namelist()
