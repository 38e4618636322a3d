"""The slip guards' compiled parts: the landing on the friction law's curve, a general pair's guard.

The slip guard (:mod:`breakwater.contact.slipguard`) changes a node's tangential step in
two cases. A step that reverses the node's slip from outside the stick band lands at zero
slip (the reversal cut). Any other step whose linear model asks for a friction force in
the law's curved zone lands where the law gives that force (:func:`land`): the
regularised law ``φ(c) = c / sqrt(|c|² + χ²)`` saturates within a few χ, and Newton on
the slip velocity c crawls along it (from stick towards a slip of 20χ, each iteration
gains about one χ: the residual fell by a factor of 2–3 per iteration for up to 20
iterations at the separately meshed Goda caisson's base corners). The linear model's
force ``f = φ(c₀) + φ'(c₀)(c₁ − c₀)`` is what the step's tangential equilibrium asks of
the law; inverting the law there, ``c = χ f / sqrt(1 − |f|²)``, gives in one step the
slip a scalar law reaches in many. At a solution the step is zero and f = φ(c₀), so the
landing is c₀ itself: the converged states are those of Newton's own iteration, and the
landing only changes the way there. It is used where the force is within the curved
zone, ``|f| < F_MAX`` (a slip of at most :data:`CURVED` χ): nearer saturation, the
inversion turns round-off and the coupling between nodes into large slips.

Beyond the curved zone, Newton crawls too, towards a slip far along the saturated law:
there ``φ(c) ≈ 1 − χ²/2c²`` and a Newton step multiplies a slip c well below the solution's
by about 1.5 (measured: a base corner of the separately meshed Goda caisson took 15
iterations from 1.2χ to 551χ, its residual halving each time). Moving such a slip (a
landing from a force within 1e-5 of saturation, or ten times Newton's proposal) failed
runs. A general pair's guard (:func:`slip_guard`) leaves it where Newton put it and moves
the law's linearisation instead: where the slip grows by more than :data:`CRAWL` times in
its direction, the next iterate's friction force is the law's tangent line at the slip
where the law gives the linear model's force, at most :data:`GROW` times Newton's
proposal (:func:`crawl_point`; :func:`breakwater.contact.forcekernels.friction`). This is
Newton with the node's force as its unknown, whose law (the inverse of φ) is smooth where
φ saturates: the next step treats the node as sliding at nearly the full friction force.
A solve that converges on such tangent lines is tested again on the law itself
(:meth:`breakwater.stepping.interfacenewton.InterfaceNewton`), so the accepted states
are the law's. A Newton's rescue (its second try) takes none. Measured, Newton iterations
before → after, every headline digit the same: the separately meshed Goda case 4114 →
3816 (its longest solve 23 → 14), the hand-meshed one 4070 → 3817, the storm sliding the
caisson 1891 → 1833, the sliding block 622 → 622; with GROW from 10 to 1e4, 3800–3880 on
both Goda cases; unbounded, 20 177 and 17 639 (about 360 rescues each; while the rescue
took crawl points too, the impact's first steps failed).

A node whose slip reverses takes crawl points at most :data:`REGROW` times Newton's
proposal for the rest of the solve (``reversed``): on the caisson meshed apart by hand
(``examples/goda_nonmatching.toml``) a node's crawl point 100× out let it slide far,
reverse, stick and crawl again, in a cycle of eight iterations, and the step was cut back.
Such nodes first took none at all, and then crawled: on a caisson of 6 mm elements on a
mound of 30 mm (``examples/goda_apart/goda_apart.geo`` with those sizes), in the impact's
first milliseconds, a node landed at zero slip by the reversal cut went from stick to
sliding through the curved zone at about twice its slip per iteration (1.8χ, 3.3χ, 6.5χ,
21χ, 372χ), the residual halving each time, the rest of the surface converged; that
was most of the 15 iterations per step there. Newton iterations of whole runs (the 6/30
mm case, ``examples/goda_apart``, the same with 10/20 mm elements) with REGROW 1 (none),
3, 10, 20, 30 and 100 (as any node): 7931/3830/4299, 6670/3773/4241, 6547/3754/4164,
7095/3749/4090, 7011/3742/4102, 7387/3722/4152; every headline digit the same.

:func:`land` is the compiled form of :func:`breakwater.contact.slipguard.land` (the
same floating-point operations), used by the conforming pairs' compiled guard
(:func:`breakwater.contact.nodalkernels.guard_steps`) and by :func:`slip_guard`, the
general pair's (:meth:`breakwater.contact.general.SurfaceForces.precheck`).
"""

from __future__ import annotations

import math

import numpy as np

from breakwater.common.jit import kernel
from breakwater.contact.forcekernels import law_line, tangential_slip

__all__ = ["CRAWL", "CURVED", "FREE", "F_MAX", "GROW", "NONE", "REGROW", "REVERSED",
           "crawl_point", "land", "slip_guard"]

#: The landing applies where the linear model's slip is within this many χ.
CURVED = 100.0
#: |φ| at a slip of CURVED χ: the landing's bound on the linear model's force.
F_MAX = CURVED / math.sqrt(1.0 + CURVED * CURVED)
#: A slip that Newton grows by more than this factor beyond the curved zone crawls.
CRAWL = 1.25
#: A crawling slip's linearisation point is at most this many times Newton's proposal...
GROW = 100.0
#: ... and this many at a node whose slip has reversed in the solve.
REGROW = 10.0
#: The crawl points a node may take (``bounds``): :data:`GROW`'s, :data:`REGROW`'s (its slip
#: reversed in this solve), none (a Newton's rescue).
FREE, REVERSED, NONE = 0, 1, 2


@kernel
def land(c0, c1, chi, out):  # type: ignore[no-untyped-def]
    """The landing of one node's tangential slip on the law's curve (compiled).

    Args:
        c0: The iterate's tangential slip velocity (components in the tangent basis).
        c1: Newton's proposal.
        chi: χ.
        out: Out: the slip where the law gives the linear model's force.

    Returns:
        Whether the force is within the curved zone (else ``out`` is the linear model's
        force f itself, :func:`~breakwater.contact.forcekernels.law_line`).
    """
    f2 = law_line(c0, c1, chi, out)
    if not f2 < F_MAX * F_MAX:
        return False
    scale = chi / math.sqrt(1.0 - f2)
    for m in range(len(c0)):
        out[m] = scale * out[m]
    return True


@kernel
def crawl_point(force, c1, chi, grow):  # type: ignore[no-untyped-def]
    """Where a crawling slip's law is linearised next (the module doc).

    Args:
        force: |f|, the linear model's force (of magnitude at least F_MAX).
        c1: Newton's proposal for the slip.
        chi: χ.
        grow: The bound's multiple of |c₁| (:data:`GROW`, or :data:`REGROW`).

    Returns:
        The slip where the law gives ``force`` (infinite from |f| ≥ 1 on), at most
        ``grow`` |c₁|, with c₁'s sign.
    """
    far = chi * force / math.sqrt(1.0 - force * force) if force < 1.0 else np.inf
    return math.copysign(min(far, grow * abs(c1)), c1)


@kernel
def slip_guard(step, v1, facet0, N0, t0, node_pos, pos_m, dv, chi, lin, lin_next,  # type: ignore[no-untyped-def]
               bounds, acts):
    """``SurfaceForces.precheck``: a general pair's slip guard on Newton's step.

    Per slave node with a start-of-step master point: the slip velocity along the
    tangent there, of the iterate (c₀) and of Newton's proposal (c₁); a reversal from
    outside the band lands at zero, any other step on the law's curve where
    :func:`land` applies (its linear model at the iterate's linearisation slip where it
    has one). The slave's tangential step is set to give the landing slip (the slip is
    linear in Δa: exact). A crawling slip is not moved: ``lin_next`` says where its law
    is linearised at the next iterate (:func:`crawl_point`).

    Args:
        step: Newton's step (changed in place where cut).
        v1: The iterate's velocities at the interface unknowns (a trailing 0).
        facet0: The slave nodes' start-of-step master facet (−1: none).
        N0: Its shape functions at ξ̄₀.
        t0: The unit tangent there.
        node_pos: Interface positions of the slave nodes.
        pos_m: Of the master facets.
        dv: β₁ Δt.
        chi: The stick band χ.
        lin: The iterate's linearisation slips (NaN: the law at the slip itself).
        lin_next: Out: the next iterate's.
        bounds: The crawl points each node may take, :data:`FREE`, :data:`REVERSED` or
            :data:`NONE` (in/out: a node whose slip reverses becomes REVERSED).
        acts: Whether the guard acts at each node (else its step stands and it has no
            crawl point: :func:`breakwater.contact.coupling.guarded_nodes`).

    Returns:
        The nodes whose step changed.
    """
    n = len(step)
    ext = np.zeros(n + 1)
    ext[:n] = step
    fixed = 0
    nm = N0.shape[1]
    a, b, out = np.empty(1), np.empty(1), np.empty(1)
    for j in range(len(facet0)):
        lin_next[j] = np.nan
        f = facet0[j]
        p0, p1 = node_pos[j, 0], node_pos[j, 1]
        if f < 0 or p0 < 0 or p1 < 0 or not acts[j]:
            continue
        c0 = tangential_slip(v1, j, f, N0, t0, node_pos, pos_m)
        c1 = c0 - dv * tangential_slip(ext, j, f, N0, t0, node_pos, pos_m)
        if c0 * c1 < 0 and abs(c0) > chi:
            target = 0.0
            bounds[j] = max(bounds[j], REVERSED)  # not a monotone crawl: a bounded one
        else:
            a[0], b[0] = (lin[j] if lin[j] == lin[j] else c0), c1
            if land(a, b, chi, out):
                if out[0] == c1:
                    continue
                target = out[0]
            else:
                if c1 * a[0] > 0 and abs(c1) > CRAWL * abs(a[0]) and bounds[j] != NONE:
                    lin_next[j] = crawl_point(abs(out[0]), c1, chi,
                                              GROW if bounds[j] == FREE else REGROW)
                continue
        ym0, ym1 = 0.0, 0.0
        for k in range(nm):
            ym0 += N0[j, k] * ext[pos_m[f, k, 0]]
            ym1 += N0[j, k] * ext[pos_m[f, k, 1]]
        t_0, t_1 = t0[j, 0], t0[j, 1]
        ys0, ys1 = ext[p0], ext[p1]
        along = (ym0 * t_0 + ym1 * t_1) + (c0 - target) / dv
        normal = ys0 * t_0 + ys1 * t_1
        step[p0] = (ys0 - t_0 * normal) + t_0 * along
        step[p1] = (ys1 - t_1 * normal) + t_1 * along
        fixed += 1
    return fixed
