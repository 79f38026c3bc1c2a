"""Transfer scenarios: TOML files with a ``[transfer]`` table (shipped ones by name, or any path).

A transfer is not a station-keeping scenario (no station, no controller cycle), so it has its own schema,
validated the same way (``geojax.params.check_table``): every problem is one ``ValueError`` line naming the
field and what is allowed, which the CLI prints before exiting with status 2.  See
``geojax/scenarios/ma2023-boom.toml`` for every key, with the reason for each marked choice.
"""

from __future__ import annotations

import dataclasses
import importlib.resources
import math
from pathlib import Path

import jax.numpy as jnp
import numpy as np

from geojax.params import NUMBER, REQUIRED, Field, check_table
from geojax.physics import constants as c
from geojax.physics.dynamics import SpacecraftState
from geojax.physics.elements import kepler_to_mee
from geojax.physics.time import TT_MINUS_TAI_S, parse_utc, tai_minus_utc_s, tt_seconds_from_utc
from geojax.scenario import ScenarioFile, tomllib
from geojax.scenario_physics import force_model
from geojax.scenario_schema import SCHEMA as SK_SCHEMA
from geojax.transfer.boom import JointLimits, MpcWeights
from geojax.transfer.quadrilateral import pair_axis_efficiency
from geojax.transfer.rollout import TransferParams
from geojax.transfer.wheels import WheelParams

MAX_ALT_KM = 1.0e6
MAX_DAYS = 3653.0  # ten years of orbit raising is a typo


def _number(default, lower=None, upper=None, lower_inclusive=False):
    return Field(NUMBER, default, lower=lower, upper=upper, lower_inclusive=lower_inclusive)


SCHEMA: dict[str, dict[str, Field]] = {
    "": {"name": Field(str, REQUIRED), "description": Field(str, "")},
    "epoch": SK_SCHEMA["epoch"],
    "orbit": {  # Keplerian start orbit from its perigee and apogee altitudes
        "perigee_alt_km": _number(REQUIRED, 0.0, MAX_ALT_KM),
        "apogee_alt_km": _number(REQUIRED, 0.0, MAX_ALT_KM),
        "i_deg": _number(REQUIRED, 0.0, 90.0, True),
        "raan_deg": _number(0.0, -360.0, 360.0 + 1e-9, True),
        "argp_deg": _number(180.0, -360.0, 360.0 + 1e-9, True),
        "true_anomaly_deg": _number(0.0, -360.0, 360.0 + 1e-9, True),
    },
    "transfer": {  # the end conditions and the guidance
        "radius_km": _number(42164.16, 6378.0, MAX_ALT_KM),
        "a_tol_km": _number(50.0, 0.0, 1e5),
        "e_end": _number(1e-3, 0.0, 1.0),
        "i_end_deg": _number(0.1, 0.0, 90.0),
        "efficiency": _number(0.5, 0.0, 1.0 + 1e-12, True),
        "deadband_km": _number(20.0, 0.0, 1e5, True),
        "max_misalignment_deg": _number(10.0, 0.0, 180.0 + 1e-9),
    },
    "spacecraft": {
        "mass_kg": _number(REQUIRED, 0.0, 1e6),
        "dry_mass_kg": _number(REQUIRED, 0.0, 1e6),
        "srp_area_m2": _number(0.0, 0.0, 1e6, True),
        "reflectivity": _number(0.0, 0.0, 1.0 + 1e-12, True),
    },
    "thruster": {
        "layout": Field(str, REQUIRED, choices=("boom", "quadrilateral")),
        # the quadrilateral's cant from its north-south axis (transfer.quadrilateral); the boom ignores it
        "cant_deg": _number(45.0, 0.0, 90.0, True),
        "thrust_n": _number(REQUIRED, 0.0, 1e5),
        "isp_s": _number(REQUIRED, 0.0, 1e6),
    },
    "attitude": {
        "slew_rate_deg_s": _number(REQUIRED, 0.0, 100.0),
        "slew_accel_deg_s2": _number(REQUIRED, 0.0, 100.0),
        # J_body of eq. (6), principal moments along the body axes (R, S, W at zero attitude); with the slew
        # acceleration it sets the wheels' torque, J x slew_accel, that the boom's eq. (8) torque competes with
        # (transfer.pointing).  Default (a choice): 2000 kg m^2 each, the inertia the shipped scenarios' slew
        # acceleration is quoted on (0.001 deg/s^2 = 0.035 N m of wheel torque).
        "inertia_kg_m2": Field(list, [2000.0, 2000.0, 2000.0], length=3),
        # The attitude thrusters that the attitude propellant is counted for (transfer.pointing): a couple of
        # 1 m arm at 220 s (hydrazine monopropellant thrusters, 220-230 s; a marked choice, both layouts).
        "rcs_arm_m": _number(1.0, 0.0, 100.0),
        "rcs_isp_s": _number(220.0, 0.0, 1e4),
        # The reaction wheels (transfer.wheels): capacity per wheel (a choice: li2022-momentum's 50 N m s), the
        # fraction of it at which the attitude thrusters above empty them, and the boom's dumping tilt of its
        # thrust line (limit 0: no dumping by the boom, the attitude thrusters do it all; the boom layout only)
        # with the law's gain (states.momentum's default, 0.01 /s).
        "wheel_capacity_nms": _number(50.0, 0.0, 1e6),
        "rcs_dump_fraction": _number(0.8, 0.0, 1.0 + 1e-12),
        "dump_angle_max_deg": _number(0.0, 0.0, 90.0, True),
        "dump_gain_per_s": _number(0.01, 0.0, 1e3, True),
    },
    "boom": {  # Table 1 joint ranges, the drive limits, link lengths and the MPC of Sec. 3
        "j1_deg": Field(list, [-90.0, 0.0], length=2),
        "j2_deg": Field(list, [75.0, 105.0], length=2),
        "j3_deg": Field(list, [-15.0, 15.0], length=2),
        "joint_rate_deg_s": _number(0.5, 0.0, 100.0),
        "joint_accel_deg_s2": _number(0.05, 0.0, 100.0),
        "d1_m": _number(0.5, 0.0, 100.0, True),
        "d2_m": _number(0.0, 0.0, 100.0, True),
        "a1_m": _number(1.0, 0.0, 100.0, True),
        "base_offset_m": Field(list, [0.0, 0.0, 1.0], length=3),
        "mpc_horizon": Field(int, 10, lower=1, upper=101, lower_inclusive=True),
        "mpc_iterations": Field(int, 20, lower=0, upper=1001, lower_inclusive=True),
        "mpc_q": _number(1.0, 0.0, 1e12),
        "mpc_q_rate": _number(0.0, 0.0, 1e12, True),
        "mpc_r": _number(1e3, 0.0, 1e12),
    },
    "forces": SK_SCHEMA["forces"],
    "integration": {"step_s": _number(120.0, 0.0, 3600.0 + 1e-9)},
    "duration": {"days": _number(250.0, 0.0, MAX_DAYS)},
}


@dataclasses.dataclass(frozen=True)
class TransferScenario(ScenarioFile):
    """A validated transfer: the file's table and epoch (``ScenarioFile``) and the rollout's parameters."""

    params: TransferParams

    @property
    def layout(self) -> str:
        return self.config["thruster"]["layout"]

    @property
    def mpc(self) -> tuple[int, int]:
        return int(self.config["boom"]["mpc_horizon"]), int(self.config["boom"]["mpc_iterations"])


def is_transfer(text: str) -> bool:
    """Whether a scenario file is a transfer (it has a ``[transfer]`` table)."""
    try:
        return isinstance(tomllib.loads(text).get("transfer"), dict)
    except tomllib.TOMLDecodeError:
        return False


def _shipped():
    return importlib.resources.files("geojax") / "scenarios"


def available() -> list[str]:
    """Names of the transfer scenarios shipped with geojax."""
    return sorted(p.name[:-5] for p in _shipped().iterdir() if p.name.endswith(".toml") and is_transfer(p.read_text()))


def load(name_or_path: str | Path, overrides: dict | None = None) -> TransferScenario:
    """Load a shipped transfer by name or a TOML file by path; ``overrides`` maps ``TABLE.KEY`` (or a top-level
    key: ``name``, ``description``) to values."""
    path = Path(name_or_path)
    if path.suffix == ".toml" or path.exists():
        if not path.is_file():
            raise ValueError(f"transfer scenario {str(name_or_path)!r}: no such file")
        text = path.read_text()
    elif str(name_or_path) in available():
        text = (_shipped() / f"{name_or_path}.toml").read_text()
    else:
        raise ValueError(f"transfer scenario {str(name_or_path)!r}: unknown; named transfers: "
                         f"{', '.join(available())} (or give the path of a .toml file)")
    try:
        raw = tomllib.loads(text)
    except tomllib.TOMLDecodeError as err:
        raise ValueError(f"{name_or_path}: not valid TOML ({err})") from None
    for dotted, value in (overrides or {}).items():
        table, _, key = dotted.rpartition(".")
        if not table and key in SCHEMA[""]:  # a top-level key: the name, the description
            raw[key] = value
            continue
        if table not in SCHEMA or not table:
            raise ValueError(f"{dotted}: not a transfer key; write it as TABLE.KEY")
        raw.setdefault(table, {})[key] = value
    return from_dict(raw)


def from_dict(raw: dict) -> TransferScenario:
    config = _validate(raw)
    utc = parse_utc(config["epoch"]["utc"])
    epoch_tt_s = tt_seconds_from_utc(utc)
    tt_minus_ut1_s = TT_MINUS_TAI_S + tai_minus_utc_s(utc.date()) - config["epoch"]["ut1_minus_utc_s"]
    return TransferScenario(config, epoch_tt_s, tt_minus_ut1_s, _params(config))


def _validate(raw: dict) -> dict:
    unknown = [t for t in raw if isinstance(raw[t], dict) and t not in SCHEMA]
    if unknown:
        raise ValueError(f"{unknown[0]}: unknown table; allowed: {', '.join(t for t in SCHEMA if t)}")
    config: dict = {}
    for table, fields in SCHEMA.items():
        given = raw if table == "" else raw.get(table, {})
        out = check_table(f"{table}." if table else "", given, fields, ignore=SCHEMA if table == "" else ())
        if table:
            config[table] = out
        else:
            config.update(out)
    orbit, craft, boom = config["orbit"], config["spacecraft"], config["boom"]
    if orbit["apogee_alt_km"] < orbit["perigee_alt_km"]:
        raise ValueError(f"orbit.apogee_alt_km: must be >= orbit.perigee_alt_km = {orbit['perigee_alt_km']:g}, "
                         f"got {orbit['apogee_alt_km']:g}")
    if craft["dry_mass_kg"] >= craft["mass_kg"]:
        raise ValueError(f"spacecraft.dry_mass_kg: must be less than spacecraft.mass_kg = {craft['mass_kg']:g}, "
                         f"got {craft['dry_mass_kg']:g}")
    if not all(isinstance(j, (int, float)) and 0.0 < j < 1e9 for j in config["attitude"]["inertia_kg_m2"]):
        raise ValueError(f"attitude.inertia_kg_m2: must be three numbers in (0, 1e9) kg m^2, "
                         f"got {config['attitude']['inertia_kg_m2']}")
    if config["attitude"]["dump_angle_max_deg"] > 0 and config["thruster"]["layout"] != "boom":
        raise ValueError(f"attitude.dump_angle_max_deg: only the boom layout can tilt its thrust line to dump "
                         f"momentum (thruster.layout = {config['thruster']['layout']!r}), got "
                         f"{config['attitude']['dump_angle_max_deg']:g}; leave it at 0")
    for key in ("j1_deg", "j2_deg", "j3_deg"):
        low, high = boom[key]
        if not -180.0 <= low <= high <= 180.0:
            raise ValueError(f"boom.{key}: must be [low, high] with -180 <= low <= high <= 180, got {boom[key]}")
    if not boom["j2_deg"][0] <= 90.0 <= boom["j2_deg"][1]:
        raise ValueError(f"boom.j2_deg: must contain joint 2's working angle 90 deg (Remark 1), got {boom['j2_deg']}")
    return config


def _params(config: dict) -> TransferParams:
    orbit, end, craft, thr, att, bm = (config[k] for k in ("orbit", "transfer", "spacecraft", "thruster", "attitude",
                                                           "boom"))
    r_p = (orbit["perigee_alt_km"] + c.R_EARTH_M / 1e3) * 1e3
    r_a = (orbit["apogee_alt_km"] + c.R_EARTH_M / 1e3) * 1e3
    mee = kepler_to_mee(0.5 * (r_p + r_a), (r_a - r_p) / (r_a + r_p), *(math.radians(orbit[k]) for k in (
        "i_deg", "raan_deg", "argp_deg", "true_anomaly_deg")))
    f = lambda x: jnp.asarray(float(x))  # noqa: E731
    rad = lambda x: jnp.asarray(np.deg2rad(np.asarray(x, dtype=float)))  # noqa: E731
    if thr["layout"] == "boom":
        lower = rad([bm["j1_deg"][0], 90.0, bm["j3_deg"][0]])
        upper = rad([bm["j1_deg"][1], 90.0, bm["j3_deg"][1]])
        pairs = jnp.array([1.0, 0.0, 0.0, 0.0])  # one thruster on the boom, along its wrist axis
    else:  # the quadrilateral: strong pairs' axis along the body's S axis, joints frozen, no boom arm
        lower = upper = rad([0.0, 90.0, 0.0])
        bm = {**bm, "d1_m": 0.0, "d2_m": 0.0, "a1_m": 0.0, "base_offset_m": [0.0, 0.0, 0.0]}
        pairs = pair_axis_efficiency(rad(thr["cant_deg"]))
    # Joint 2 is held at its working angle 90 deg (Remark 1, Fig. 11); its Table 1 range is checked above.
    three = lambda x: jnp.full(3, float(x))  # noqa: E731
    return TransferParams(
        initial=SpacecraftState(jnp.asarray(mee), f(craft["mass_kg"]), f(0.0)),
        forces=force_model({"forces": config["forces"], "spacecraft": craft}),
        dry_mass_kg=f(craft["dry_mass_kg"]), thrust_n=f(thr["thrust_n"]), isp_s=f(thr["isp_s"]), pair_efficiency=pairs,
        r_geo_m=f(end["radius_km"] * 1e3), a_tol_m=f(end["a_tol_km"] * 1e3), e_end=f(end["e_end"]),
        i_end_rad=rad(end["i_end_deg"]), deadband_m=f(end["deadband_km"] * 1e3),
        efficiency=f(end["efficiency"]),
        max_misalignment_rad=rad(end["max_misalignment_deg"]),
        slew_rate_rad_s=rad(att["slew_rate_deg_s"]), slew_accel_rad_s2=rad(att["slew_accel_deg_s2"]),
        inertia_kg_m2=jnp.asarray(att["inertia_kg_m2"], dtype=float), rcs_arm_m=f(att["rcs_arm_m"]),
        rcs_isp_s=f(att["rcs_isp_s"]),
        joints=JointLimits(lower, upper, three(np.deg2rad(bm["joint_rate_deg_s"])),
                           three(np.deg2rad(bm["joint_accel_deg_s2"]))),
        weights=MpcWeights(three(bm["mpc_q"]), three(bm["mpc_q_rate"]), three(bm["mpc_r"])),
        d1_m=f(bm["d1_m"]), d2_m=f(bm["d2_m"]), a1_m=f(bm["a1_m"]), base_offset_m=jnp.asarray(bm["base_offset_m"]),
        wheels=WheelParams(f(att["wheel_capacity_nms"]), f(att["rcs_dump_fraction"]), rad(att["dump_angle_max_deg"]),
                           f(att["dump_gain_per_s"])),
    )
