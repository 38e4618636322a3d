"""Writing the results of a run: the step history, fields and snapshots.

Everything here is written by rank 0 only, except the ParaView fields (VTX/ADIOS2),
which every rank writes collectively. Small files (``summary.json``, ``case.toml``,
``.npz`` snapshots, figures) are written atomically (:mod:`breakwater.common.files`, which
also names the files), so a reader never sees half a file. The step history
``history.csv`` grows during the run: one whole row per write call, flushed every
step, so it can be read (or plotted) while the run goes on.

Output files of a run (in the output directory):

- ``case.toml``: the resolved case, when the case layer gives it.
- ``history.csv``: one row per accepted step, plus the row of the static state at t = 0.
- ``summary.json``: headline numbers, solver statistics, versions.
- ``fields_<body>.bp``: displacement, velocity, stress tensor, von Mises and σ_yy stress
  of each body, as discontinuous P2 fields (exact for P2 displacements), for ParaView.
- ``contact_<pair>.bp``: contact pressure, normal gap, slip, slip velocity and
  friction traction of each contact pair, as P2 fields on the interface (a general
  pair's on its slave surface): :class:`PairFields`.
- ``static.npz``: the static state (P1 nodal values per body, ``<body>_<field>``, the
  stresses averaged over the cells at a vertex, and
  each pair's nodal state, ``contact_<pair>_<field>``:
  :func:`breakwater.outputs.monitor.interface_state`).
- ``snapshot_max_ux.npz``: the same at the instant of the largest |u_x| of the first
  probe.
- ``figures/``: see :mod:`breakwater.outputs.figures`.
- ``checkpoint.npz``: the latest checkpoint, with ``output.checkpoint_interval`` > 0
  (see :mod:`breakwater.outputs.checkpoint`).

``summary.json`` is written when the run starts (``finished: false``, ``status:
"running"``), again at every checkpoint, and at the end (``status`` ``finished``,
``failed`` or ``interrupted``), so a folder whose run was killed still says that it
did not finish; while running it names its process (:mod:`breakwater.common.liveness`),
so that a reader can tell a run killed by SIGKILL from one going on.
"""

from __future__ import annotations

import io
import os
import pathlib
from collections.abc import Mapping, Sequence
from typing import IO

import dolfinx
import numpy as np
from dolfinx import fem
from mpi4py import MPI

from breakwater import forms  # type: ignore[attr-defined]  # breakwater.forms maps to forms/
from breakwater.common.errors import cannot_write
from breakwater.common.files import HISTORY, atomic_savez, atomic_write_text, read_history, writing
from breakwater.common.parallel import on_rank_zero
from breakwater.model.mesh import group_tag
from breakwater.model.model import ContactModel
from breakwater.model.pairs import Pair
from breakwater.outputs.checkpoint import match_nodes
from breakwater.outputs.historyrows import HistoryRows
from breakwater.outputs.section import section, section_plane
from breakwater.outputs.vertexaverage import VertexAverage
from breakwater.outputs.vtxfiles import VTXFiles

__all__ = ["SCALARS", "VECTORS", "BodyFields", "FieldWriter", "HistoryWriter", "PairFields",
           "RunFiles", "read_history", "snapshot_arrays"]

# --- step history -----------------------------------------------------------------

class HistoryWriter:
    """The step history as CSV, written by rank 0 one whole row at a time.

    Each row is written by one ``write`` call and flushed, so a run killed at any
    moment leaves whole rows only (the operating system keeps what was written).

    Args:
        path: The CSV file (overwritten, unless ``keep_rows`` is given).
        columns: Column names, in order.
        comm: Communicator; only its rank 0 writes.
        keep_rows: Resume: keep the header and the first ``keep_rows`` rows of the
            existing file (cut atomically; the rest is dropped), read them into
            :attr:`kept` (on every rank) and append after them.

    Raises:
        ValueError: (``keep_rows``) The file has other columns or fewer whole rows.

    """

    def __init__(self, path: str | pathlib.Path, columns: Sequence[str], comm: MPI.Comm,
                 keep_rows: int | None = None) -> None:
        self.path = pathlib.Path(path)
        self.columns = tuple(columns)
        self.comm = comm
        self.rows = 0
        self.kept = HistoryRows(self.columns)
        self._file: IO[str] | None = None
        self._failed = False  # a write raised (a full disk)
        if keep_rows is None:
            def start() -> None:
                with writing(self.path):
                    self._file = open(self.path, "w", encoding="utf-8", newline="")
                    self._write(",".join(self.columns))

            on_rank_zero(comm, start)
            return
        self.kept = on_rank_zero(comm, lambda: self._cut(keep_rows))
        self.rows = keep_rows

        def reopen() -> None:
            with writing(self.path):
                self._file = open(self.path, "a", encoding="utf-8", newline="")

        on_rank_zero(comm, reopen)

    def _cut(self, keep_rows: int) -> HistoryRows:
        """Keep the header and ``keep_rows`` whole rows, atomically; return the rows."""
        header = ",".join(self.columns) + "\n"
        lines: list[str] = []
        with open(self.path, encoding="utf-8", newline="") as f:
            if f.readline() != header:
                raise ValueError(f"{self.path}: the columns differ from the run's")
            for line in f:
                if len(lines) == keep_rows or not line.endswith("\n"):
                    break
                lines.append(line)
        if len(lines) < keep_rows:
            raise ValueError(f"{self.path} holds {len(lines)} whole rows, fewer than the "
                             f"{keep_rows} of the checkpoint")
        # repr(float) is read back exactly (NumPy's parser rounds correctly, as float()
        # does), without a list of Python floats per row (a storm's 250 000 rows); read
        # before the file is cut, so that a row that does not read leaves it as it was.
        try:
            values = np.loadtxt(io.StringIO("".join(lines)), delimiter=",", ndmin=2) \
                if lines else np.zeros((0, len(self.columns)))
        except ValueError as e:
            raise ValueError(f"{self.path}: a kept row does not read ({e})") from e
        if values.shape != (len(lines), len(self.columns)):
            raise ValueError(f"{self.path}: a row has other columns than the header")
        atomic_write_text(self.path, header + "".join(lines))
        return HistoryRows(self.columns, values)

    def _write(self, line: str) -> None:
        assert self._file is not None
        try:
            self._file.write(line + "\n")  # one call per whole row
            self._file.flush()
        except OSError:
            self._failed = True  # raised (the run's error): close() does not say it again
            raise

    def append(self, row: Mapping[str, float]) -> None:
        """Write one row (every column must be present); collective.

        Raises:
            OutputError: The row cannot be written (e.g. a full disk), on every rank.
        """
        def write() -> None:
            if self._file is not None:
                with writing(self.path):
                    self._write(",".join(repr(float(row[c])) for c in self.columns))

        on_rank_zero(self.comm, write)
        self.rows += 1

    def sync(self) -> None:
        """Force the rows written so far to disk (before a checkpoint refers to them).

        Collective; raises :class:`~breakwater.common.errors.OutputError` on every rank.
        """
        def sync() -> None:
            if self._file is not None:
                with writing(self.path):
                    try:
                        self._file.flush()
                        os.fsync(self._file.fileno())
                    except OSError:
                        self._failed = True
                        raise

        on_rank_zero(self.comm, sync)

    def close(self) -> None:
        """Close the file (not collective: a write error here is not raised)."""
        if self._file is not None:
            file, self._file = self._file, None
            try:
                file.close()
            except OSError as e:  # the rows were flushed one by one: the last one lost
                if self._failed:  # (the error raised by a write already says so)
                    return
                import logging

                logging.getLogger("breakwater.run.simulation").warning(
                    "%s", cannot_write(self.path, e))


# --- fields of the bodies ---------------------------------------------------------

COMPONENTS = {"stress_xx": (0, 0), "stress_xy": (0, 1), "stress_zz": (2, 2)}
"""The stress components of the snapshots beside ``stress_yy`` (indices in the 3 × 3 tensor)."""

class BodyFields:
    """Displacement, velocity and stresses of one body as discontinuous P_k fields.

    ``stress`` is the full 3 × 3 tensor (in 2D plane strain with σ_zz = λ tr ε), with
    ``von_mises`` and ``stress_yy`` (the paper's Figs. 17 and 22) beside it.

    The stress of a P_k displacement is a discontinuous P_(k-1) field, so
    discontinuous P_k holds every field exactly (no projection or averaging).

    Args:
        model: The contact model.
        index: Body index.

    """

    def __init__(self, model: ContactModel, index: int) -> None:
        body = model.bodies[index]
        self.name = body.spec.name
        self.filename = f"fields_{self.name}.bp"
        sub = body.submesh
        gdim = model.gdim
        degree = body.V.ufl_element().embedded_superdegree
        self.gdim = gdim
        # 3D: the figures' section across z, the same for every body (section_plane).
        self.section_z = section_plane(model) if gdim == 3 else 0.0
        self.u = fem.Function(body.V, name="u_out")
        self.v = fem.Function(body.V, name="v_out")
        Vd = fem.functionspace(sub, ("Discontinuous Lagrange", degree, (gdim,)))
        S = fem.functionspace(sub, ("Discontinuous Lagrange", degree))
        self.displacement = fem.Function(Vd, name="displacement")
        self.velocity = fem.Function(Vd, name="velocity")
        T = fem.functionspace(sub, ("Discontinuous Lagrange", degree, (3, 3)))
        self.stress = fem.Function(T, name="stress")
        self.von_mises = fem.Function(S, name="von_mises")
        self.stress_yy = fem.Function(S, name="stress_yy")
        λ0, μ0 = body.spec.material.lame
        # Constants on the submesh: one compiled kernel serves every body.
        λ = fem.Constant(sub, dolfinx.default_scalar_type(λ0))
        μ = fem.Constant(sub, dolfinx.default_scalar_type(μ0))
        σ3 = forms.stress_3d(self.u, λ, μ)
        X = S.element.interpolation_points
        self._σ = fem.Expression(σ3, X)
        self._vm = fem.Expression(forms.von_mises(σ3), X)
        self._syy = fem.Expression(σ3[1, 1], X)
        self.functions = [self.displacement, self.velocity, self.stress, self.von_mises,
                          self.stress_yy]
        self._p1: tuple[fem.FunctionSpace, fem.FunctionSpace, fem.FunctionSpace,
                        VertexAverage] | None = None
        # The fast path of update: the P_k nodes of a cell are the discontinuous
        # space's (the same element, the same points), so displacement and velocity are
        # copies of the nodal values, and von Mises and σ_yy follow from the stress at
        # the same points (their Expressions stay the reference: update_interpolated).
        V = body.V
        cg, dg = V.dofmap.list, Vd.dofmap.list
        same = (cg.shape == dg.shape and V.dofmap.index_map_bs == Vd.dofmap.index_map_bs
                and np.array_equal(S.dofmap.list, dg) and np.array_equal(T.dofmap.list, dg)
                and V.ufl_element().basix_element.points.tolist()
                == Vd.ufl_element().basix_element.points.tolist())
        self._copy = (cg.ravel().astype(np.int64), dg.ravel().astype(np.int64)) if same \
            else None

    def update(self, u: fem.Function, v: fem.Function | None = None) -> None:
        """Evaluate the fields of the state ``(u, v)`` of this body.

        The nodal values of u and v copied, the stress interpolated (its Expression),
        von Mises sqrt(3/2 s:s) and σ_yy from the stress at the same points: the
        numbers of :meth:`update_interpolated` to round-off.
        """
        if self._copy is None:
            self.update_interpolated(u, v)
            return
        self.u.x.array[:] = u.x.array
        cg, dg = self._copy
        gdim = self.gdim
        self.displacement.x.array.reshape(-1, gdim)[dg] = u.x.array.reshape(-1, gdim)[cg]
        if v is None:
            self.velocity.x.array[:] = 0.0
        else:
            self.velocity.x.array.reshape(-1, gdim)[dg] = v.x.array.reshape(-1, gdim)[cg]
        self.stress.interpolate(self._σ)
        σ = self.stress.x.array.reshape(-1, 3, 3)
        mean = (σ[:, 0, 0] + σ[:, 1, 1] + σ[:, 2, 2]) / 3.0
        s = σ.copy()
        for i in range(3):
            s[:, i, i] -= mean
        self.von_mises.x.array[:] = np.sqrt(1.5 * np.einsum("kij,kij->k", s, s))
        self.stress_yy.x.array[:] = σ[:, 1, 1]

    def update_interpolated(self, u: fem.Function, v: fem.Function | None = None) -> None:
        """:meth:`update` by interpolation into each field's space (the reference)."""
        self.u.x.array[:] = u.x.array
        self.v.x.array[:] = 0.0 if v is None else v.x.array
        self.displacement.interpolate(self.u)
        self.velocity.interpolate(self.v)
        self.stress.interpolate(self._σ)
        self.von_mises.interpolate(self._vm)
        self.stress_yy.interpolate(self._syy)

    def nodal(self) -> dict[str, np.ndarray] | None:
        """P1 nodal values of the current fields, gathered on rank 0 (None elsewhere).

        The stresses are discontinuous: at a vertex, the volume-weighted average of
        its cells' values (:class:`~breakwater.outputs.vertexaverage.VertexAverage`,
        each field averaged: von Mises of the cells, not of the averaged tensor), the
        same on any number of ranks.

        Returns:
            On rank 0: ``x`` (n, 2) vertex coordinates, ``triangles`` (m, 3),
            ``ux``, ``uy``, ``von_mises``, ``stress_yy`` and the stress tensor's
            components ``stress_xx``, ``stress_xy``, ``stress_zz`` (n,; σ_zz = λ tr ε
            in plane strain; σ_xz = σ_yz = 0 there, not written). In 3D the same on the
            section z = :attr:`section_z` (:func:`~breakwater.outputs.section.section`):
            its points and triangles, the values interpolated there.
        """
        sub = self.u.function_space.mesh
        if self._p1 is None:
            S1 = fem.functionspace(sub, ("Lagrange", 1))
            self._p1 = (fem.functionspace(sub, ("Lagrange", 1, (self.gdim,))), S1,
                        fem.functionspace(sub, ("Lagrange", 1, (3, 3))), VertexAverage(S1))
        V1, S1, T1, average = self._p1
        u1 = fem.Function(V1)
        u1.interpolate(self.u)  # continuous: its vertex values
        scalars = {name: average(f, S1) for name, f in (("von_mises", self.von_mises),
                                                        ("stress_yy", self.stress_yy))}
        σ = average(self.stress, T1).reshape(-1, 3, 3)  # T1 has S1's dof layout
        for name, (i, j) in COMPONENTS.items():
            scalars[name] = σ[:, i, j]
        imap = S1.dofmap.index_map
        nloc = imap.size_local
        tdim = sub.topology.dim
        ncells = sub.topology.index_map(tdim).size_local
        # (A rank may hold no cell of a body: keep the shape of its empty block.)
        dofs = S1.dofmap.list[:ncells]
        cells = imap.local_to_global(dofs.ravel()).reshape(dofs.shape)
        local = {
            "gidx": imap.local_to_global(np.arange(nloc, dtype=np.int32)),
            "x": S1.tabulate_dof_coordinates()[:nloc, :self.gdim],
            "cells": cells,
            "ux": u1.x.array.reshape(-1, self.gdim)[:nloc, 0],
            "uy": u1.x.array.reshape(-1, self.gdim)[:nloc, 1],
            **{k: a[:nloc] for k, a in scalars.items()},
        }
        parts = sub.comm.gather(local, root=0)
        if parts is None:
            return None
        n = imap.size_global
        out: dict[str, np.ndarray] = {k: np.zeros(n) for k in ("ux", "uy", *scalars)}
        out["x"] = np.zeros((n, self.gdim))
        for part in parts:
            for k in out:
                out[k][part["gidx"]] = part[k]
        cells = np.vstack([part["cells"] for part in parts])
        if self.gdim == 3:
            x3 = out.pop("x")
            xy, triangles, values = section(x3, cells, out, self.section_z)
            return {"x": xy, "triangles": triangles, **values}
        if cells.shape[1] == 4:  # quadrilaterals (tensor-product order): two triangles each
            cells = np.vstack([cells[:, [0, 1, 3]], cells[:, [0, 3, 2]]])
        out["triangles"] = cells.astype(np.int64)
        return out


SCALARS = ("pressure", "gap")
"""The scalar contact fields written for ParaView (every pair)."""
VECTORS = ("slip", "slip_velocity", "friction_traction")
"""The vector contact fields written for ParaView."""


def group_fields(model: ContactModel, group: str, degree: int, nodes: np.ndarray,
                 body: int | None = None) -> tuple[dict[str, fem.Function], np.ndarray]:
    """The contact fields as P_degree Functions on the submesh of a facet group.

    Also returns the index of each of ``nodes`` among their (scalar) dofs. The fields
    are :data:`SCALARS` and :data:`VECTORS`.

    Args:
        model: The contact model.
        group: The facet group (gmsh physical name).
        degree: The Lagrange degree of the fields.
        nodes: The points where the contact state is evaluated, shape ``(n, gdim)``.
        body: The group's facets on this body only (its index; None: all). A general
            pair's slave surface may be a group on both bodies (the master's side too,
            ``slave_surface = master_surface``): on meshes apart its master facets'
            nodes are no slave nodes (the run failed after its static state, "the mesh
            differs from the checkpoint's: no stored node at ...").
    """
    msh, gdim = model.mesh, model.gdim
    fdim = msh.topology.dim - 1
    assert model.mesh_data.facet_tags is not None
    facets = model.mesh_data.facet_tags.find(group_tag(model.mesh_data, group, fdim))
    if body is not None:
        assert model.mesh_data.cell_tags is not None
        name = model.bodies[body].spec.name
        cells = model.mesh_data.cell_tags.find(group_tag(model.mesh_data, name, fdim + 1))
        on = np.zeros(msh.topology.index_map(fdim + 1).size_local
                      + msh.topology.index_map(fdim + 1).num_ghosts, bool)
        on[cells] = True
        msh.topology.create_connectivity(fdim, fdim + 1)
        f2c = msh.topology.connectivity(fdim, fdim + 1)
        facets = facets[[bool(on[f2c.links(f)].any()) for f in facets]]
    sub = dolfinx.mesh.create_submesh(msh, fdim, facets)[0]
    S = fem.functionspace(sub, ("Lagrange", degree))
    V = fem.functionspace(sub, ("Lagrange", degree, (gdim,)))
    values = {k: fem.Function(S, name=k) for k in SCALARS}
    values.update({k: fem.Function(V, name=k) for k in VECTORS})
    # The blocked space has the scalar space's dof layout: one index per node.
    x = S.tabulate_dof_coordinates()[:, :gdim]
    extent = max(float(np.ptp(nodes, axis=0).max()), 1e-300) if len(nodes) else 1.0
    return values, match_nodes(nodes, x, 1e-8 * extent)


class PairFields:
    """The contact state of one pair as P_k fields for ParaView (``contact_<name>.bp``).

    The pair's facet group (a conforming pair's interface, a general pair's slave
    surface: :meth:`~breakwater.model.pairs.Pair.field_nodes`) forms a mesh of its own
    (a submesh of dimension one less); its P_k nodes are the pair's nodes, where the
    fields hold the pair's nodal state (:meth:`~breakwater.model.pairs.Pair.field_values`;
    interpolated between them). Fields: ``pressure`` and ``gap`` (scalars), ``slip``,
    ``slip_velocity`` and ``friction_traction`` (vectors). At a conforming pair's
    nodes the law acts (the Gauss–Lobatto points of the interface measure), so nodal
    values are exact; a general pair's residual integrates the law at its own points,
    and its ``pressure`` is their dual-basis projection onto the slave nodes
    (:func:`breakwater.contact.slavepoints.nodal_pressure`), whose integral is the
    residual's ∫p, where positive, else 0 (a negative value is a weight of the
    projection past the contact's edge, not a tension).

    Args:
        model: The contact model.
        pair: The pair (one of the stepper's
            :attr:`~breakwater.stepping.gn22.GN22.contacts`).
    """

    def __init__(self, model: ContactModel, pair: Pair) -> None:
        self.filename = f"contact_{pair.name}.bp"
        self.pair = pair
        where = pair.field_nodes()
        degree = model.bodies[where.body].V.ufl_element().embedded_superdegree
        self.values, self._index = group_fields(model, where.group, degree, where.x,
                                                    where.body)
        self.functions = list(self.values.values())

    def update(self, u: Sequence[fem.Function], v: Sequence[fem.Function] | None = None
               ) -> None:
        """Evaluate the fields of the state ``(u, v)`` (one Function per body; collective)."""
        state = self.pair.field_values(u, v)
        for k, f in self.values.items():
            shape = (len(self._index), f.function_space.dofmap.index_map_bs)
            f.x.array.reshape(shape)[:] = state[k][self._index].reshape(shape)


class FieldWriter:
    """ParaView output: one VTX (ADIOS2 ``.bp``) file per body and per contact pair.

    Args:
        fields: The fields of each body (``fields_<body>.bp``).
        interfaces: The fields of each contact pair (``contact_<pair>.bp``).
        directory: Output directory.
        comm: The communicator of the mesh.

    """

    def __init__(self, fields: Sequence[BodyFields],
                 interfaces: Sequence[PairFields],
                 directory: pathlib.Path, comm: MPI.Comm, expected: int = 0) -> None:
        self.fields = list(fields)
        self.interfaces = list(interfaces)
        files: list[BodyFields | PairFields] = [*self.fields, *self.interfaces]
        self.paths = [directory / f.filename for f in files]
        self.files = VTXFiles(comm, self.paths, [f.functions for f in files], expected)

    def write(self, t: float, u: Sequence[fem.Function], v: Sequence[fem.Function]) -> None:
        """Write the state (one Function per body) at time ``t`` (collective).

        Raises:
            OutputError: A file cannot be written (a full disk), on every rank; the
                files keep the times written before, and nothing more is written.
        """
        if self.files.failed is not None:
            return
        for f, ui, vi in zip(self.fields, u, v, strict=True):
            f.update(ui, vi)
        for i in self.interfaces:
            i.update(u, v)
        self.files.write(t)

    def close(self) -> None:
        """Close the files (collective; an OutputError when they cannot be)."""
        self.files.close()


def snapshot_arrays(fields: Sequence[BodyFields], u: Sequence[fem.Function],
                    interface: Mapping[str, np.ndarray], time: float, comm: MPI.Comm,
                    ) -> dict[str, np.ndarray] | None:
    """The arrays of a snapshot file, on rank 0 (None elsewhere); collective.

    Keys: ``time``, ``bodies`` (names), ``<body>_<field>`` for the fields of
    :meth:`BodyFields.nodal`, and the interface arrays as given.
    """
    out: dict[str, np.ndarray] = {"time": np.array(time),
                                  "bodies": np.array([f.name for f in fields])}
    for f, ui in zip(fields, u, strict=True):
        f.update(ui)
        nodal = f.nodal()
        if nodal is not None:
            out.update({f"{f.name}_{k}": a for k, a in nodal.items()})
    if comm.rank != 0:
        return None
    out.update(interface)
    return out


class RunFiles:
    """The files a run writes as it steps: history, ParaView fields, nodal snapshots.

    ``history.csv`` gets one row per call, the ParaView files the states given (every
    ``field_interval`` steps; none when 0), the ``.npz`` snapshots a state each.

    Args:
        model: The contact model.
        pairs: The pairs (the stepper's :attr:`~breakwater.stepping.gn22.GN22.contacts`:
            ``contact_<name>.bp``).
        directory: The output folder.
        field_interval: Steps between ParaView outputs (0: none).

    """

    def __init__(self, model: ContactModel, pairs: Sequence[Pair], directory: pathlib.Path,
                 field_interval: int) -> None:
        self.directory, self.comm, self.interval = directory, model.comm, field_interval
        self.bodies = [BodyFields(model, i) for i in range(len(model.bodies))]
        self.interfaces = [PairFields(model, p) for p in pairs] if field_interval > 0 else []
        self.history: HistoryWriter | None = None
        self.writer: FieldWriter | None = None

    def open_history(self, columns: Sequence[str], keep_rows: int | None = None
                     ) -> HistoryRows:
        """Start ``history.csv``, or (resume) keep its first ``keep_rows`` rows.

        Returns:
            The rows kept (see :class:`HistoryWriter`).
        """
        self.history = HistoryWriter(self.directory / HISTORY, columns, self.comm, keep_rows)
        return self.history.kept

    def open_fields(self, resume: bool = False, steps: int = 0) -> list[str]:
        """Start the ParaView files (when fields are written); collective.

        Args:
            resume: Rename the files of the interrupted part first:
                ``<file>.part<k>.bp`` (a VTX file cannot be appended to).
            steps: The steps planned (a warning when their fields will not fit).

        Returns:
            The names of the files set aside.
        """
        if self.interval <= 0:
            return []
        def set_aside() -> list[str]:
            parts: list[str] = []
            for filename in [f.filename for f in self.bodies] + \
                    [f.filename for f in self.interfaces]:
                path = self.directory / filename
                if resume and path.exists():
                    k = 1
                    while (target := path.with_suffix(f".part{k}.bp")).exists():
                        k += 1
                    os.replace(path, target)
                    parts.append(target.name)
            return parts

        parts = on_rank_zero(self.comm, set_aside)
        self.writer = FieldWriter(self.bodies, self.interfaces, self.directory, self.comm,
                                  1 + -(-steps // self.interval))
        return parts

    @property
    def field_files(self) -> list[str]:
        """Names of the ParaView files being written."""
        return [p.name for p in self.writer.paths] if self.writer else []

    def write_fields(self, t: float, u: Sequence[fem.Function], v: Sequence[fem.Function]
                     ) -> None:
        """Write the state at ``t`` to the ParaView files, if any (collective)."""
        if self.writer is not None:
            self.writer.write(t, u, v)

    def write_snapshot(self, filename: str, u: Sequence[fem.Function],
                       interface: Mapping[str, np.ndarray], time: float) -> None:
        """Write the nodal snapshot of the state ``u`` (collective; rank 0 writes)."""
        arrays = snapshot_arrays(self.bodies, u, interface, time, self.comm)
        on_rank_zero(self.comm, lambda: arrays is not None and bool(
            atomic_savez(self.directory / filename, **arrays)))

    def close(self) -> None:
        """Close the history and the ParaView files."""
        if self.history is not None:
            self.history.close()
        if self.writer is not None:
            self.writer.close()
