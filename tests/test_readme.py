"""The README's practitioner example runs as written (on a calibrated UR5e, read from the
controller stand-in) and prints what the README shows."""

import contextlib
import io
import json
import re
from pathlib import Path

import pytest

README = Path(__file__).resolve().parents[1] / "README.md"


def fenced_block(text, marker, language):
    """The fenced block of ``language`` that follows the HTML comment ``marker``."""
    match = re.search(rf"<!-- {marker} -->\n```{language}\n(.*?)```", text, re.S)
    assert match, f"README.md has no ```{language} block after <!-- {marker} -->"
    return match.group(1)


def real_ur5e_calibration():
    """The calibration a real UR5e's controller reported (tests/data/real_calibrations), as
    the corrections of its calibration.conf, which the controller stand-in serves."""
    from real_calibrations import FILE

    from dqlab.models import ur5e
    from dqlab.ur.calibration import CalibrationConf

    stored = json.loads(FILE.read_text(encoding="utf-8"))["calibrations"]
    real = stored["UR5e (ur_calibration log)"]
    nominal = ur5e().links
    deltas = [tuple(float(value - getattr(link, field))
                    for value, link in zip(real[f"dh_{key}"], nominal, strict=True))
              for key, field in (("theta", "theta_offset"), ("a", "a"), ("d", "d"),
                                 ("alpha", "alpha"))]
    return CalibrationConf(*deltas, calibration_status=2)


def rounding_as_zero(text):
    """The text with every number below 1e-12 in size written 0: the errors at the level of
    rounding, which differ between machines and between the compiled and numpy paths; and
    each run of spaces one space (a table's columns are as wide as those errors)."""
    text = re.sub(r"-?\d+(?:\.\d+)?e-\d+",
                  lambda m: "0" if abs(float(m.group())) < 1e-12 else m.group(), text)
    return re.sub(r" +", " ", text)


def test_readme_practitioner_example_runs_and_prints_what_it_shows():
    """The README's block as written, on a calibrated UR5e: its controller is the stand-in
    serving a real UR5e's calibration, at the stand-in's address and port."""
    pytest.importorskip("mujoco")          # the example ends with a MuJoCo run
    from dqlab.ur import ControllerStandIn

    text = README.read_text(encoding="utf-8")
    code = fenced_block(text, "practitioner-example", "python")
    shown = fenced_block(text, "practitioner-output", "text")
    address = 'CONTROLLER = "192.168.1.10"'
    assert code.count(address) == 1 and code.count("port=30002") == 1
    printed = io.StringIO()
    with ControllerStandIn("ur5e", calibration=real_ur5e_calibration()) as standin:
        code = code.replace(address, f"CONTROLLER = {standin.host!r}").replace(
            "port=30002", f"port={standin.secondary_port}")
        with contextlib.redirect_stdout(printed):
            exec(compile(code, str(README), "exec"), {"__name__": "readme_example"})
    assert rounding_as_zero(printed.getvalue()) == rounding_as_zero(shown)


def test_readme_names_exist():
    """Every ``dqlab.`` name the README's prose and code mention is importable."""
    import importlib

    text = README.read_text(encoding="utf-8")
    names = set(re.findall(r"\bdqlab(?:\.\w+)+", text))
    assert "dqlab.quaternion.quaternion_from_xyzw" in names
    for name in sorted(names):
        parts = name.split(".")
        for cut in range(len(parts), 0, -1):     # the longest importable module prefix
            try:
                obj = importlib.import_module(".".join(parts[:cut]))
                break
            except ImportError:
                continue
        for attribute in parts[cut:]:
            obj = getattr(obj, attribute)        # AttributeError: a name that rotted
