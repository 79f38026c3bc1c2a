"""The filter's measurement updates at a step's end: which trackers measure (``tracking_weights``: schedule and
elevation mask) and each one's measurements simulated from the truth and processed in Joseph form
(``measurement_updates``)."""

from __future__ import annotations

import jax
import jax.numpy as jnp

from geojax.navigation import ekf
from geojax.navigation.leaves import sigma_bias, stations_of
from geojax.navigation.measurements import MODELS
from geojax.navigation.schedule import Schedule, station_schedules, tracking_weight
from geojax.navigation.state import N_STATE, Layout
from geojax.navigation.stations import Station, station_eci_m
from geojax.physics.elements import wrap_angle
from geojax.physics.frames import ecef_to_eci


def trackers(layout: Layout):
    """(tracker, its measurement types): the stations in order, then the receiver (-1)."""
    return [(i, kinds) for i, kinds in enumerate(layout.stations)] + ([(-1, ("gnss",))] if layout.gnss else [])


def tracking_weights(layout: Layout, nav: dict, t_s, r_eci_m, earth_angle_rad):
    """[n_trackers] 1.0 where a tracker measures at ``t_s``: in its schedule and, for a station, the true satellite
    at or above its elevation mask (geometric elevation: the down leg's light time turns it by 2 arc seconds)."""
    out = []
    if layout.stations:
        stations = stations_of(nav)
        los = r_eci_m - station_eci_m(stations, earth_angle_rad)  # [n, 3]
        up = ecef_to_eci(stations.enu_ecef[:, 2], earth_angle_rad)
        visible = jnp.sum(up * los, axis=-1) >= jnp.sin(nav["station_mask_rad"]) * jnp.linalg.norm(los, axis=-1)
        out.append(jax.vmap(tracking_weight, in_axes=(None, 0))(t_s, station_schedules(nav)) * visible)
    if layout.gnss:
        plan = Schedule(nav["gnss_cadence_s"], nav["gnss_pass_s"], nav["gnss_phase_s"], nav["gnss_outages_s"])
        out.append(tracking_weight(t_s, plan)[None])
    return jnp.concatenate(out)


def measurement_updates(layout: Layout, mu, filtered, weights, nav, truth, angle, bias, key):
    """The measurement updates of one step end, one tracker at a time (Joseph form, weighted by ``weights``):
    ``filtered`` = (x, execution, P, NIS sum, its dof, measurements used) after them."""
    x, execution, p, nis_sum, nis_dof, used, bias_estimate = filtered
    n = p.shape[0]
    n_b = n - N_STATE
    all_stations = stations_of(nav) if layout.stations else None
    rv = x
    offset = 0
    for place, (i, kinds) in enumerate(trackers(layout)):
        station = (jax.tree_util.tree_map(lambda leaf, i=i: leaf[i], all_stations) if i >= 0
                   else Station(jnp.zeros(3), jnp.eye(3)))
        weight = weights[place]

        def h(y, station=station, kinds=kinds):
            return jnp.concatenate([MODELS[kind].h(y, station, angle) for kind in kinds])

        size = sum(MODELS[kind].size for kind in kinds)
        sigma = jnp.concatenate([jnp.broadcast_to(sigma_bias(nav, i, kind)[0], (MODELS[kind].size,))
                                 for kind in kinds])
        z = h(truth) + bias[offset:offset + size] + sigma * jax.random.normal(jax.random.fold_in(key, offset), (size,))
        jac, predicted = jax.jacfwd(lambda y, h=h: (h(y), h(y)), has_aux=True)(rv)
        if n_b:  # the estimated biases' part of the prediction: z = h(x) + b
            predicted = predicted + bias_estimate[offset:offset + size]
        innovation = z - predicted
        at = 0
        for kind in kinds:  # the azimuth's residual wrapped to (-pi, pi]
            if kind == "angles":
                innovation = innovation.at[at].set(wrap_angle(innovation[at]))
            at += MODELS[kind].size
        h_x = jnp.zeros((size, n)).at[:, :6].set(jac)
        if n_b:
            h_x = h_x.at[:, N_STATE + offset:N_STATE + offset + size].set(jnp.eye(size))
        delta, p, s = ekf.measurement_update(jnp.zeros(n), p, innovation, h_x, jnp.diag(sigma**2), weight)
        rv = rv + delta[:6]
        execution = execution + delta[6:N_STATE]
        if n_b:
            bias_estimate = bias_estimate + delta[N_STATE:]
        nis_sum = nis_sum + weight * ekf.nis(innovation, s)
        nis_dof = nis_dof + weight * size
        used = used + weight * size
        offset += size
    return rv, execution, p, nis_sum, nis_dof, used, bias_estimate
