"""Per-step outputs against the evaluations they replace: ParaView fields, probes.

:meth:`breakwater.outputs.writers.BodyFields.update` copies the nodal values of u and v
into the discontinuous P2 fields (the same element's points) and takes von Mises and
σ_yy from the interpolated stress at the same points; the interpolations into each
field's space (:meth:`BodyFields.update_interpolated`) are the reference. Equal to 1e-12
of each field's largest value (round-off: the basis functions at the points are
Kronecker deltas to 1e-16, and von Mises is the same formula in another order), at a
random state with and without velocity, every body of the Goda case, serially and on 2
ranks. :class:`breakwater.outputs.probes.Probes` evaluates its point probes (and the
conforming pair probes' two) in one compiled sum; each probe's own evaluation is the
reference.
"""

from __future__ import annotations

import numpy as np
from mpi4py import MPI

from breakwater.casefile.case import load_case
from breakwater.outputs.writers import BodyFields
from breakwater.stepping.gn22 import GN22

COMM = MPI.COMM_WORLD


def _arrays(f: BodyFields) -> list[np.ndarray]:
    return [g.x.array.copy() for g in f.functions]


def test_goda_body_fields_equal_interpolations() -> None:
    model, *_ = load_case(None, ["mesh.refinement=0.7"]).build(COMM)
    rng = np.random.default_rng(7 + COMM.rank)
    for index in range(len(model.bodies)):
        fields = BodyFields(model, index)
        assert fields._copy is not None  # P2 on affine cells: the fast path
        u, v = (model.functions(name)[index] for name in ("u_test", "v_test"))
        for f, scale in ((u, 1e-3), (v, 1e-2)):
            f.x.array[:] = scale * rng.standard_normal(len(f.x.array))
            f.x.scatter_forward()
        for velocity in (v, None):
            fields.update(u, velocity)
            got = _arrays(fields)
            for g in fields.functions:
                g.x.array[:] = np.nan
            fields.update_interpolated(u, velocity)
            ref = _arrays(fields)
            for g, a, b in zip(fields.functions, got, ref, strict=True):
                scale = COMM.allreduce(float(np.abs(b).max(initial=0.0)), op=MPI.MAX)
                assert scale > 0 or (velocity is None and g.name == "velocity"), g.name
                np.testing.assert_allclose(a, b, rtol=0, atol=1e-12 * scale, err_msg=g.name)


def test_goda_probes_equal_point_evaluations() -> None:
    # The probes' values from one compiled sum (breakwater.outputs.probes.probe_sums)
    # against each probe's own evaluation (Probes.local_reference: φ·u per point probe,
    # a conforming pair probe's two point probes): the same products, summed in order,
    # so equal to 1e-14 of the largest; the Goda case's two gauges and two corner
    # pair probes, at random states, serially and on 2 ranks (the owner's share only).
    from breakwater.outputs.probes import Probes

    case = load_case(None, ["mesh.refinement=0.7"])
    model, _, output, _ = case.build(COMM)
    stepper = GN22(model, 1e-4)
    try:
        probes = Probes(model, output, stepper.contacts)
        assert len(probes.points) == 2 and len(probes.pairs) == 2 and all(probes._fused)
        rng = np.random.default_rng(3 + COMM.rank)
        for _ in range(3):
            for f in stepper.u:
                f.x.array[:] = 1e-3 * rng.standard_normal(len(f.x.array))
                f.x.scatter_forward()
            got = np.concatenate(probes.local(stepper.u))
            ref = np.concatenate(probes.local_reference(stepper.u))
            got, ref = (COMM.allreduce(x, op=MPI.SUM) for x in (got, ref))
            assert np.all(ref != 0)
            np.testing.assert_allclose(got, ref, rtol=0, atol=1e-14 * np.abs(ref).max())
    finally:
        stepper.destroy()
