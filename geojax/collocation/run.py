"""A cluster's run (``simulate_cluster``): its satellites' closed loops in one compiled program
(``loop.cluster``), each satellite's metrics as a lone run's, and the distance between them.

Each satellite draws its errors from the run's seed folded with a stable id of its name (CRC-32), never its
place in the file, so that adding a satellite changes no other satellite's draws.
"""

from __future__ import annotations

import functools
import time
import zlib
from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from geojax.control import mpc, mpc_cluster
from geojax.control.base import Controller
from geojax.export import recorder
from geojax.loop.cluster import SeparationRecord, pairs, separation_metrics, simulate_cluster as cluster_loop
from geojax.loop.metrics import STATUS_TEXT, cycle_table, summarize
from geojax.loop.simulate import Records
from geojax.physics.constants import SIDEREAL_DAY_S
from geojax.physics.propagate import for_lanes
from geojax.runner.rollout import Result, compiler_options
from geojax.runner.setup import prepare, reference
from geojax import states as parts
from geojax.scenario import Scenario, from_dict, to_toml

# What the summary prints of each satellite, beside its status.
SATELLITE_METRICS = ("dv_per_year_mps", "max_abs_dlon_deg", "max_abs_dlat_deg")


class ClusterResult(NamedTuple):
    """A cluster's run: its satellites' results as a batch (``satellites``: leading axis satellite, in the file's
    order, named ``names``), each pair's per-cycle separations (``separation``: [cycle, pair], pairs in
    ``loop.cluster.pairs`` order) and the cluster's metrics (``metrics``, units in the names)."""

    names: tuple[str, ...]
    satellites: Result
    separation: SeparationRecord
    metrics: dict
    scenario: Scenario
    seed: int
    alert_km: float
    wall_s: float
    uncontrolled: bool = False  # every satellite's free drift (``geojax propagate``)
    flown: tuple = ()  # the satellites' scenarios as flown (with the null controller where ``uncontrolled``)

    @property
    def pair_names(self) -> tuple[str, ...]:
        return tuple(f"{self.names[i]}_{self.names[j]}" for i, j in pairs(len(self.names)))

    def metric_table(self) -> dict[str, float]:
        """The cluster's metrics as floats, each pair's by its names (``min_separation_km_A_B``)."""
        out = {}
        for name, value in self.metrics.items():
            if name.startswith("pair_"):
                out.update({f"{name[5:]}_{pair}": float(v) for pair, v in zip(self.pair_names, value)})
            else:
                out[name] = float(value)
        return out

    def summary(self) -> list[str]:
        """What ``geojax simulate`` prints of a cluster: the least separation, when and between which pair, the
        operator's view of it, then each pair and each satellite."""
        m = self.metric_table()
        i, j = pairs(len(self.names))[int(m["min_separation_pair"])]
        meanings = self.satellites.status_meanings
        lines = [f"{self.scenario.name}: {len(self.names)} satellites ({', '.join(self.names)}), "
                 f"{'free drift' if self.uncontrolled else self.scenario.controller + ' each'}, {self.scenario.days:g} days in {self.wall_s:.1f} s",
                 f"  min_separation_km {m['min_separation_km']:.4f} on day {m['min_separation_day']:.3f} between "
                 f"{self.names[i]} and {self.names[j]}; below_alert_h {m['below_alert_h']:.2f} "
                 f"(closer than alert_km {self.alert_km:g})",
                 f"  from the estimates at cycle starts: min_estimated_separation_km "
                 f"{m['min_estimated_separation_km']:.4f}, max_separation_error_km {m['max_separation_error_km']:.4f}"]
        for pair in self.pair_names:
            lines.append(f"  pair {pair}: min_separation_km {m['min_separation_km_' + pair]:.4f}, below_alert_h "
                         f"{m['below_alert_h_' + pair]:.2f}")
        for k, name in enumerate(self.names):
            values = ", ".join(f"{key} {float(self.satellites.metrics[key][k]):.4g}" for key in SATELLITE_METRICS)
            lines.append(f"  {name}: status {int(self.satellites.status[k])} "
                         f"({meanings[int(self.satellites.status[k])]}), {values}")
        return lines

    def satellite(self, k: int) -> Result:
        """Satellite ``k``'s own ``Result``, as ``simulate`` of it alone returns one (its files: ``save_oem``)."""
        one = lambda tree: None if tree is None else jax.tree_util.tree_map(lambda x: x[k], tree)  # noqa: E731
        r = self.satellites
        return r._replace(metrics=one(r.metrics), status=r.status[k], records=one(r.records), final=one(r.final),
                          params=one(r.params), scenario=(self.flown or self.scenario.satellites)[k], seed=self.seed,
                          ephemeris=None if r.ephemeris is None else recorder.Ephemeris(*map(one, r.ephemeris)))

    def save_oem(self, path, **options) -> list:
        """One CCSDS OEM per satellite, ``STEM-NAME.oem`` beside ``path`` (and each planner's burns beside it;
        ``options``: ``Result.save_oem``'s); a run made with ``ephemeris`` holds every step."""
        from pathlib import Path

        path = Path(path)
        return [written for k, name in enumerate(self.names)
                for written in self.satellite(k).save_oem(path.with_name(f"{path.stem}-{name}{path.suffix}"),
                                                          object_name=name, **options)]

    def save_maneuvers(self, path) -> list:
        """One CCSDS OPM of the burns flown per satellite, ``STEM-NAME.opm`` beside ``path``."""
        from pathlib import Path

        path = Path(path)
        return [self.satellite(k).save_maneuvers(path.with_name(f"{path.stem}-{name}{path.suffix}"))
                for k, name in enumerate(self.names)]

    def cycles(self) -> dict[str, np.ndarray]:
        """Per cycle: the cluster's least separation over its pairs (``min_separation_km``), each pair's, and the
        operator's view at the cycle starts."""
        out = {"min_separation_km": np.min(self.separation.min_m, axis=1) / 1e3}
        for k, pair in enumerate(self.pair_names):
            out[f"min_separation_km_{pair}"] = self.separation.min_m[:, k] / 1e3
            out[f"estimated_separation_km_{pair}"] = self.separation.estimated_start_m[:, k] / 1e3
        return out

    def save(self, path) -> object:
        """The cluster's file: ``/metrics`` (the cluster's), ``/cycles`` (its separations per cycle),
        ``/satellite_metrics`` (each satellite's metrics and status, [satellite]) and ``/satellite_cycles``
        (each satellite's ``/cycles``, [satellite, cycle]); the attribute ``satellites`` names them in order."""
        from geojax import store

        one = lambda k: jax.tree_util.tree_map(lambda x: x[k], self.satellites.records)  # noqa: E731
        tables = [cycle_table(one(k), self.satellites.states) for k in range(len(self.names))]
        groups = {"metrics": self.metric_table(), "cycles": self.cycles(),
                  "satellite_metrics": {**self.satellites.metrics, "status": self.satellites.status},
                  "satellite_cycles": {key: np.stack([t[key] for t in tables]) for key in tables[0]}}
        attrs = {"kind": "collocation", "scenario": self.scenario.name, "epoch_tt_s": self.scenario.epoch_tt_s,
                 "seed": self.seed, "satellites": ",".join(self.names), "status_codes": STATUS_TEXT}
        dims = {"cycles": ("cycle",), "satellite_metrics": ("satellite",), "satellite_cycles": ("satellite", "cycle")}
        return store.write_h5(path, groups, to_toml(self.scenario.config), self.wall_s, attrs=attrs, dims=dims)


def satellite_keys(seed: int, names) -> jax.Array:
    """Each satellite's key: the seed's, folded with a stable id of the satellite's name."""
    base = jax.random.key(seed)
    return jnp.stack([jax.random.fold_in(base, zlib.crc32(name.encode()) | (1 << 31)) for name in names])


def _drifting(sc: Scenario) -> Scenario:
    """``sc`` with the null controller (its validated table less the keys it left unset)."""
    table = {k: {key: v for key, v in t.items() if v is not None} if isinstance(t, dict) else t
             for k, t in sc.config.items()}
    return from_dict({**table, "controller": {"kind": "none"}})


def coordinated(scenarios) -> Controller | None:
    """The controller of clusters (``scenarios``) whose ``[collocation]`` asks for one program for all their
    satellites (``coordinated``: the MPC's, ``control.mpc_cluster``); None where each satellite plans alone."""
    asked = {sc.config["collocation"]["coordinated"] for sc in scenarios}
    if len(asked) > 1:
        raise ValueError("collocation.coordinated: sets the compiled program; one value per sweep")
    if not asked.pop():
        return None
    return mpc_cluster.coordinated_controller(mpc.shape_of([m.config["controller"] for sc in scenarios
                                                            for m in sc.satellites]))


@functools.partial(jax.jit, static_argnames=("controller", "step_s", "dynamics", "keep_steps", "states",
                                             "steps_per_cycle", "ephemeris"))
def cluster_rollout(params, keys, shared, reference_env, alert_m, min_separation_m=None, *, controller, step_s,
                    dynamics, keep_steps, states, steps_per_cycle, ephemeris: bool = False):
    """One cluster's closed loop, its satellites' metrics and its separations: (final, records, separation,
    satellite metrics, cluster metrics), and with ``ephemeris`` every satellite's ``export.recorder.Ephemeris``;
    ``min_separation_m`` [] what a coordinated plan keeps (``loop.cluster``).  Pure, vmappable over clusters."""
    if ephemeris:
        states = recorder.with_recording(states)
    if reference_env is not None:  # each satellite its own uncontrolled reference (their targets differ)
        own = jax.vmap(lambda p: reference(p, reference_env, step_s, dynamics, controller.reference_cycles))(params)
        shared = shared._replace(reference=own)
    final, records, separation = cluster_loop(controller, params, shared, keys, step_s=step_s, alert_m=alert_m,
                                              dynamics=dynamics, keep_steps=keep_steps, states=states,
                                              min_separation_m=min_separation_m)
    kept = None
    if ephemeris:
        records, kept = recorder.split(records)
        states = states[:-1]  # the recording's own model (``recorder.TRUTH``) last
    metrics = jax.vmap(lambda p, f, c: summarize(p, f, Records(c, None), step_s, steps_per_cycle, states,
                                                      controller.metrics))(
        params, final, records.cycles)
    out = final, records, separation, metrics, separation_metrics(separation, steps_per_cycle * step_s)
    return (*out, kept) if ephemeris else out


def simulate_cluster(sc: Scenario, seed: int = 0, keep_steps: bool = False, uncontrolled: bool = False,
                     ephemeris: bool = False) -> ClusterResult:
    """The closed loops of the cluster ``sc`` (a scenario with ``[[satellites]]``) in one compiled call;
    ``uncontrolled``: its free drift (every satellite with the null controller, ``geojax propagate``);
    ``ephemeris``: keep every satellite's states per step, for its CCSDS files (``ClusterResult.save_oem``)."""
    if not sc.satellites:
        raise ValueError(f"{sc.name}: not a cluster; give [[satellites]] tables (docs/collocation.md)")
    start = time.perf_counter()
    members = [_drifting(m) if uncontrolled else m for m in sc.satellites]
    batch = prepare(members, None if uncontrolled else coordinated([sc]))
    names = tuple(member.name for member in sc.satellites)
    alert_km = float(sc.config["collocation"]["alert_km"])
    steps_per_cycle = batch.shared.env.earth_angle_rad.shape[1]
    args = (batch.params, satellite_keys(seed, names), batch.shared,
            batch.reference_env if batch.reference_per_sample else None, jnp.asarray(alert_km * 1e3),
            jnp.asarray(sc.config["collocation"]["min_separation_km"] * 1e3))
    static = dict(controller=batch.controller, step_s=batch.step_s, dynamics=for_lanes(batch.dynamics, len(names)),
                  keep_steps=keep_steps, states=batch.states, steps_per_cycle=steps_per_cycle, ephemeris=ephemeris)
    # compiled as a single run's program is (its compilation is the wait: ``runner.rollout.compiler_options``)
    out = cluster_rollout.lower(*args, **static).compile(compiler_options(1, batch.controller))(*args)
    final, records, separation, metrics, cluster, *kept = jax.tree_util.tree_map(np.asarray, jax.block_until_ready(out))
    status = metrics.pop("status")
    wall_s = time.perf_counter() - start
    satellites = Result(metrics, status, records, final, jax.tree_util.tree_map(np.asarray, batch.params),
                        batch.step_s, wall_s, states=batch.states,
                        parts=parts.parts_of(batch.states, parts.named(sc.satellites[0].config)),
                        ephemeris=kept[0] if kept else None)
    return ClusterResult(names, satellites, separation, cluster, sc, seed, alert_km, wall_s, uncontrolled,
                         tuple(members))


def plot(result: ClusterResult, folder, dpi: int = 150) -> list:
    """The cluster's figures in ``folder``: the e and i vector planes and the separation per cycle."""
    from pathlib import Path

    from geojax.plots.collocation import plot_separation, plot_vectors

    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    one = lambda k: jax.tree_util.tree_map(lambda x: x[k], result.satellites.records)  # noqa: E731
    cycles = [cycle_table(one(k), result.satellites.states) for k in range(len(result.names))]
    targets = [member.config["station"] for member in result.scenario.satellites]
    stem = result.scenario.name
    return [plot_vectors(result.names, cycles, targets, folder / f"{stem}_vectors.png", stem, dpi=dpi),
            plot_separation(result.pair_names, result.separation.min_m / 1e3, SIDEREAL_DAY_S, result.alert_km,
                            folder / f"{stem}_separation.png", stem, dpi=dpi)]
