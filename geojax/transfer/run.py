"""Running transfers: one (``run``) or a batch (``batch_runner``), with their metrics as plain numbers."""

from __future__ import annotations

import math
import time
from typing import NamedTuple

import jax
import numpy as np

from geojax.physics.constants import G0_MPS2, SECONDS_PER_DAY
from geojax.physics.propagate import environment_grid
from geojax.compilation import Compilations
from geojax.progress import TICK_S, Progress
from geojax.transfer import pointing, report, rollout
from geojax.transfer.rollout import STATUS_MEANINGS, Static, TransferParams, transfer
from geojax.transfer.scenario import TransferScenario


class TransferResult(NamedTuple):
    metrics: dict  # names carry units; see ``metrics``
    records: dict  # per record interval, edge units (deg, days, km), numpy
    wall_s: float
    scenario: TransferScenario | None = None  # what its file records (``transfer.report``)

    # What ``geojax transfer`` writes (``--out``), prints and draws (``--plots``): its report's functions.
    save, summary, plot = report.save, report.summary, report.plot


def static_for(sc: TransferScenario, days: float | None = None, record_every_s: float = SECONDS_PER_DAY) -> Static:
    """The loop's shape: the time limit (``days``, default the scenario's) in steps, grouped into records (the
    limit is rounded up to a whole number of record intervals)."""
    days = sc.days if days is None else days
    if not days > 0:
        raise ValueError(f"duration.days: must be > 0, got {days:g}")
    steps = max(1, round(days * SECONDS_PER_DAY / sc.step_s))
    per_record = min(steps, max(1, round(record_every_s / sc.step_s)))
    n_records = math.ceil(steps / per_record)
    return Static(sc.step_s, n_records, per_record, *sc.mpc)


def env_grid(sc: TransferScenario, static: Static):
    """Sun, Moon and Earth angle at every RK4 stage, shared by every transfer of a batch (same epoch)."""
    return environment_grid(sc.epoch_tt_s, sc.epoch_tt_s, sc.tt_minus_ut1_s, static.step_s, static.n_records,
                            static.steps_per_record, sc.config["forces"]["ephemeris"])


def run(sc: TransferScenario, days: float | None = None, record_every_s: float = SECONDS_PER_DAY,
        progress: bool | None = False) -> TransferResult:
    """One transfer, compiled and run; metrics and records as numpy.

    The run is flown in equal blocks of records (``_block``), one compiled program for all (``rollout.advance``),
    so that ``progress`` (``geojax.progress.Progress``'s ``enabled``; default none) can count the days flown;
    the numbers are those of one call of ``rollout.transfer`` to the last bits (1e-15 relative: XLA orders a
    block's operations a little differently from the whole loop's; ``tests/test_transfer.py``)."""
    start = time.perf_counter()
    static = static_for(sc, days, record_every_s)
    grid = env_grid(sc, static)
    block = _block(static.n_records)
    unit = "days" if record_every_s == SECONDS_PER_DAY else "records"
    advance = jax.jit(rollout.advance, static_argnums=3)
    carry, pieces = rollout.initial_carry(sc.params), []
    with Progress(static.n_records, unit, enabled=progress, tick_s=TICK_S) as bar, Compilations() as log:
        bar.phase("compiling or loading from the cache, and flying the first block")
        for first in range(0, static.n_records, block):
            carry, records = advance(sc.params, carry, jax.tree_util.tree_map(lambda x: x[first:first + block], grid),
                                     static)
            pieces.append(jax.device_get(records))
            bar.update(block)
            if first == 0:  # the first block compiled the program: the rate starts after it
                bar.restart(f"{log.made()} and flew the first {block} {unit} in {time.perf_counter() - start:.1f} s")
    final, records = rollout.ended(carry, jax.tree_util.tree_map(lambda *x: np.concatenate(x), *pieces), static)
    return TransferResult(metrics(jax.device_get(final), sc.params), record_table(records),
                          time.perf_counter() - start, sc)


PROGRESS_BLOCKS = 20


def _block(n_records: int) -> int:
    """Records per block of a run with progress: the largest divisor of ``n_records`` that cuts it into at least
    ``PROGRESS_BLOCKS`` blocks (equal blocks: one compiled program), or all of them where it is that short."""
    if n_records <= PROGRESS_BLOCKS:
        return 1
    return max(d for d in range(1, n_records // PROGRESS_BLOCKS + 1) if n_records % d == 0)


def stack(params_list) -> TransferParams:
    """One batch of transfers (leading axis) from a list of ``TransferParams`` (any mix of layouts)."""
    return jax.tree_util.tree_map(lambda *leaves: jax.numpy.stack(leaves), *params_list)


def run_batch(sc: TransferScenario, params, days: float | None = None, record_every_s: float = SECONDS_PER_DAY):
    """A batch of transfers sharing ``sc``'s epoch, step and time limit, in one compilation: vmapped, the batch
    sharded over the local devices (one XLA CPU device per core, ``geojax.parallel``), the environment grid
    replicated.  Returns (metrics of arrays [batch], records [batch, n_records], wall s, compile s)."""
    from geojax.parallel import replicate, shard_batch

    start = time.perf_counter()
    static = static_for(sc, days, record_every_s)
    size = jax.tree_util.tree_leaves(params)[0].shape[0]
    if size % jax.device_count() == 0:
        params = shard_batch(params)
    grid = replicate(env_grid(sc, static))
    batched = jax.jit(jax.vmap(transfer, in_axes=(0, None, None)), static_argnums=2)
    compiled = batched.lower(params, grid, static).compile()
    compile_s = time.perf_counter() - start
    final, records = jax.device_get(compiled(params, grid))
    return metrics(final, params), record_table(records), time.perf_counter() - start, compile_s


def metrics(final, params) -> dict:
    """Scalar results of one transfer (or arrays over a batch); units in the names."""
    m0, m1 = np.asarray(params.initial.mass_kg), np.asarray(final.craft.mass_kg)
    stats = final.stats
    firing = np.asarray(stats.firing_s)
    steps = np.maximum(np.asarray(stats.track_steps), 1)
    rms = np.sqrt(np.asarray(stats.track_sq_rad2) / steps)
    out = {
        "status": np.asarray(final.status),
        "transfer_days": np.asarray(final.t_end_s) / SECONDS_PER_DAY,
        "propellant_kg": m0 - m1,
        "dv_mps": np.asarray(final.craft.dv_mps),
        "rocket_dv_mps": np.asarray(params.isp_s) * G0_MPS2 * np.log(m0 / m1),
        "firing_days": firing / SECONDS_PER_DAY,
        # the share of the thrust the firing rule asked for that was delivered along its direction (time lost
        # to slewing and the cosine of the misalignment both count), and the cosine alone while firing
        "thrust_efficiency": np.asarray(stats.aligned_s) / np.maximum(firing + np.asarray(stats.lost_to_slew_s), 1e-30),
        "cosine_efficiency": np.asarray(stats.aligned_s) / np.maximum(firing, 1e-30),
        "lost_to_slew_days": np.asarray(stats.lost_to_slew_s) / SECONDS_PER_DAY,
        "max_coupling_torque_nm": np.asarray(stats.torque_max_nm),
        # eq. (8) on the body (pointing): the momentum it hands the wheels, and the time it beat their torque
        "torque_impulse_nms": np.asarray(stats.torque_impulse_nms),
        "torque_overpowered_days": np.asarray(stats.overpowered_s) / SECONDS_PER_DAY,
        # the attitude thrusters' propellant for the slews (pointing.attitude_propellant_kg), and what they would
        # burn holding eq. (8)'s torque instead of the wheels (a bound on its momentum dumping)
        "slew_impulse_nms": np.asarray(stats.slew_impulse_nms),
        "attitude_propellant_kg": np.asarray(pointing.attitude_propellant_kg(
            stats.slew_impulse_nms, params.rcs_arm_m, params.rcs_isp_s)),
        "torque_hold_propellant_kg": np.asarray(pointing.attitude_propellant_kg(
            stats.torque_impulse_nms, params.rcs_arm_m, params.rcs_isp_s)),
    }
    # the paper's "fuel consumption" counts the attitude adjustment's with the electric thrusters'
    out["total_propellant_kg"] = out["propellant_kg"] + out["attitude_propellant_kg"]
    # the reaction wheels (transfer.wheels): the largest momentum a wheel held, the net momentum the external
    # torques left (undumped), the attitude thrusters' unloading and its propellant (booked apart from the total
    # above, as the slews' bound is), the boom's dumping torque and the Delta-V its tilts put across the line
    w = final.wheels
    peak = np.max(np.asarray(w.max_abs_nms), axis=-1)
    out.update({
        "max_wheel_momentum_nms": peak,
        "wheels_saturated": peak > np.asarray(params.wheels.capacity_nms),
        "net_torque_momentum_nms": np.linalg.norm(np.asarray(w.torque_eci_nms), axis=-1),
        "wheel_momentum_end_nms": np.linalg.norm(np.asarray(w.h_body_nms), axis=-1),
        "rcs_dumps": np.asarray(w.rcs_dumps),
        "rcs_dumped_nms": np.asarray(w.rcs_dumped_nms),
        "dump_propellant_kg": np.asarray(pointing.attitude_propellant_kg(w.rcs_dumped_nms, params.rcs_arm_m,
                                                                         params.rcs_isp_s)),
        "tilt_torque_impulse_nms": np.asarray(w.tilt_impulse_nms),
        "tilt_cross_dv_mps": np.asarray(w.tilt_cross_mps),
    })
    for j in range(3):
        out[f"j{j + 1}_track_max_deg"] = np.rad2deg(np.asarray(stats.track_max_rad)[..., j])
        out[f"j{j + 1}_track_rms_deg"] = np.rad2deg(rms[..., j])
    return out


def record_table(records) -> dict:
    deg = np.rad2deg
    out = {"t_days": np.asarray(records.t_s) / SECONDS_PER_DAY, "a_km": np.asarray(records.a_m) / 1e3,
           "e": np.asarray(records.e), "i_deg": deg(records.i_rad), "mass_kg": np.asarray(records.mass_kg),
           "dv_mps": np.asarray(records.dv_mps), "on_fraction": np.asarray(records.on_fraction),
           "misalignment_deg": deg(records.misalignment_rad), "torque_nm": np.asarray(records.torque_nm),
           "pair": np.asarray(records.pair)}
    for k, axis in enumerate("xyz"):  # body axes: R, S, W at zero attitude
        out[f"wheel_{axis}_nms"] = np.asarray(records.wheel_nms)[..., k]
    for name, values in (("wished_{}_deg", records.wished_rad), ("body_{}_deg", records.body_rad),
                         ("body_rate_{}_deg_s", records.body_rate_rad_s)):
        out[name.format("azimuth")], out[name.format("elevation")] = deg(values[..., 0]), deg(values[..., 1])
    for j in range(3):
        out[f"theta{j + 1}_deg"] = deg(records.theta_rad[..., j])
        out[f"target{j + 1}_deg"] = deg(records.target_rad[..., j])
        out[f"omega{j + 1}_deg_s"] = deg(records.omega_rad_s[..., j])
    return out


def describe_status(code: int) -> str:
    return STATUS_MEANINGS[int(code)]
