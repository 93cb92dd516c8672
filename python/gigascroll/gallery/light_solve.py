"""Lux targets on the *total* illuminance, interreflections included (the `light` command's
`--targets total`).

A light spec's lux target is solved on the direct illuminance (Lambert's formula, exact and
free: room/lights.py). A pale room adds tens of percent to it, and a conservator who asks
for 50 lx means 50 lx measured. The total illuminance is still linear in the lights'
radiances (light transport is linear in the emission, the albedos fixed), so with the k
lights that have a painting target measured one at a time (each alone, at its direct-solved
radiance: M[i, j] = mean lux on light i's painting from light j) and the other emitters
together (F[i]), the scales s that meet every target solve M s = t - F. Each measurement is
a photon pass and bake (`measure`), so this costs k + 1 of them, plus the final one.
"""

from __future__ import annotations

import copy

import numpy as np

from ..room.spec import RoomSpec

__all__ = ["solve_total_targets", "total_target_lights"]


def total_target_lights(room: RoomSpec) -> list[int]:
    """Indices into room.lights of the lights whose lux target is on a painting slot (targets
    at given points, as the built-in rooms' own lights have, stay direct)."""
    return [j for j, light in enumerate(room.lights)
            if light.lux is not None and light.painting is not None]


def _slot_of(room: RoomSpec, which) -> int:
    if isinstance(which, str):
        names = [s.name for s in room.paintings]
        if which in names:
            return names.index(which)
        return [s.painting for s in room.paintings].index(which)
    return int(which)


def _only(room: RoomSpec, on: set[str]) -> RoomSpec:
    """A copy of the room in which only the surfaces named in `on` emit."""
    r = copy.copy(room)
    r.surfaces = [copy.copy(s) for s in room.surfaces]
    for s in r.surfaces:
        if s.name not in on:
            s.emission = (0.0, 0.0, 0.0)
    return r


def solve_total_targets(room: RoomSpec, measure) -> dict:
    """Scales the emission of room's painting-targeted lights (in place) so that each one's
    painting gets its lux target as total mean illuminance. `measure(room) -> {slot: mean
    lux}` lights and measures a room. Returns {"scales": {light name: s}, "passes": n}.
    ValueError when the targets cannot be met together (a scale would be <= 0)."""
    targets = total_target_lights(room)
    if not targets:
        return {"scales": {}, "passes": 0}
    lights = [room.lights[j] for j in targets]
    names = [light.name for light in lights]
    slots = [_slot_of(room, light.painting) for light in lights]
    emitting = {s.name for s in room.surfaces if max(s.emission) > 0}
    k = len(lights)
    m = np.zeros((k, k))
    for j, name in enumerate(names):
        lux = measure(_only(room, {name}))
        m[:, j] = [lux[i] for i in slots]
    fixed = emitting - set(names)
    f = np.zeros(k)
    if fixed:
        lux = measure(_only(room, fixed))
        f = np.array([lux[i] for i in slots])
    t = np.array([float(light.lux) for light in lights])
    try:
        s = np.linalg.solve(m, t - f)
    except np.linalg.LinAlgError:
        raise ValueError("the lux targets cannot be solved on the total illuminance: two "
                         "lights light their paintings alike (give them one target)") from None
    if not np.all(np.isfinite(s)) or np.any(s <= 0):
        bad = [n for n, x in zip(names, s) if not x > 0]
        raise ValueError(f"the lux targets cannot be met together on the total illuminance "
                         f"(lights {', '.join(map(repr, bad))} would need to emit nothing or "
                         f"less; the other lights already give their paintings more)")
    for light, scale in zip(lights, s):
        surface = next(x for x in room.surfaces if x.name == light.name)
        surface.emission = tuple(float(e * scale) for e in surface.emission)
        for key in ("radiance", "lumens"):
            light.details[key] = float(light.details[key] * scale)
        light.details["total_scale"] = float(scale)
    return {"scales": dict(zip(names, map(float, s))), "passes": k + bool(fixed)}
