"""The calibrations of real UR arms stored in ``tests/data/real_calibrations`` (their origins
are in the README there), as :class:`dqlab.robot.Robot` objects in standard DH: the
controller's parameters, or its model's published ones plus the corrections of its
``calibration.conf``."""

import json
from pathlib import Path

from dqlab import models
from dqlab.robot import Link, Robot

FILE = Path(__file__).resolve().parent / "data" / "real_calibrations" / "real_calibrations.json"


def real_calibrations() -> dict:
    """Every stored calibration: name -> Robot (the model's joint limits, no tool)."""
    stored = json.loads(FILE.read_text(encoding="utf-8"))["calibrations"]
    robots = {}
    for name, entry in stored.items():
        nominal = getattr(models, entry["model"].lower())()
        if "dh_d" in entry:
            theta, a, d, alpha = (entry[f"dh_{k}"] for k in ("theta", "a", "d", "alpha"))
        else:
            theta, a, d, alpha = (
                [getattr(lk, field) + delta for lk, delta in zip(nominal.links,
                                                                  entry[f"delta_{key}"],
                                                                  strict=True)]
                for key, field in (("theta", "theta_offset"), ("a", "a"), ("d", "d"),
                                   ("alpha", "alpha")))
        robots[name] = Robot([Link(a=a[i], alpha=alpha[i], d=d[i], theta_offset=theta[i],
                                   limits=nominal.links[i].limits) for i in range(6)],
                             convention="dh", name=name)
    return robots
