"""femp_post: a femp run's output as numpy arrays, for plot scripts.

    import sys; sys.path.insert(0, "contrib")     # or copy this file
    import femp_post
    run = femp_post.Run("output")                  # an Output/Directory
    pool = run.melt_pool()         # {"time": array, "length": ..., ...}
    cd = run.probe_line("CD")      # last output; run.probe_line("CD", 2)
    cd.time, cd["s"], cd["T"]      # its time (s) and columns
    g = run.grid()                 # last grid output, VTU or HDF5 alike
    g.time, g.centres, g["T"]      # cell centres (C x dim, m), cell values
    p = run.points()               # material points where written
    p.positions, p["temperature"]

Needs Python 3 and numpy (Debian: python3-numpy); h5py (python3-h5py) only
for runs written with Output/Format = hdf5. Without numpy the CSV files,
the parameter files and the printed lines still load (the scripts of the
default test suite rely on that): a column is then a Column, a list of
floats or strings with numpy's tolist(); the field outputs need numpy. SI units throughout, as in the
files (doc/output.md lists the fields and their units). What it reads:

  melt_pool.csv             Run.melt_pool()     the time series of the pool
  probe_points.csv          Run.probe_points()  the probe points' series
  absorption.csv            Run.absorption()    ray-traced laser series
  solid_energy.csv          Run.solid_energy()  the solid's energy accounts
  solid_probes.csv          Run.solid_probes()  the solid's probe points
  parameters.prm            Run.parameters(), Run.parameter(name)
  probe_line_<L>_<n>.csv    Run.probe_line(L, n), Run.probe_line_names()
  track_shape_<n>.csv       Run.track_shape(n)
  track_bead.csv            Run.track_bead()
  porosity.csv, pores.csv   Run.porosity(), Run.pores(n)  builds: pores
                            pore_neighbourhood_summary(Run.grid(n)): the
                            stress next to the pore cells and away
  tracks.csv, layers.csv    Run.tracks(), Run.layers()    builds: per track
  layer_cost.csv            Run.layer_cost()    builds: wall and size per layer
  any other femp CSV        read_csv(path)
  a scene or parameter file read_parameters(path): "Section/Name" -> text
  femp's printed lines      read_printed(log, pattern): the numbers of the
                            lines of a log or test output that match
  grid.pvd / grid.xdmf      Run.outputs(): [(n, time)] of the field outputs
  grid_<n>.pvtu (VTU), grid_mesh*.h5 + grid_<n>.h5 (HDF5)   Run.grid(n)
  points_<n>.pvtu, points_<n>.h5                             Run.points(n)

Every table is a Table: a dict of column name -> 1D float array, with
.time (the '# time = ... s' line of the file, else None) and .header (its
'#' lines). n = None means the last output; n < 0 counts from the end.

What femp prints (the progress lines, the end report, a test program's
checks) is read by a regular expression, one row per matching line:

    steps = femp_post.read_printed("run.log",
        r"^t =\s*(?P<t>\S+) s\s+step.*wall\s+(?P<wall>\S+) s")
    steps["t"], steps["wall"], steps.lines   # floats; line numbers
"""
import base64
import glob
import os
import re
import struct
import xml.etree.ElementTree as ET
import zlib

try:
    import numpy as np
except ImportError:  # CSV, parameters and printed lines work without it
    np = None


class Column(list):
    """A column of a Table when numpy is missing: a list (a slice is a
    Column too) with numpy's tolist()."""

    def tolist(self):
        return list(self)

    def __getitem__(self, i):
        item = list.__getitem__(self, i)
        return Column(item) if isinstance(i, slice) else item


def _array(values, dtype=None):
    if np is None:
        return Column(values)
    return np.array(values, dtype=dtype) if dtype else np.array(values)


def _need_numpy(what):
    if np is None:
        raise ImportError("femp_post: %s needs numpy (Debian: python3-numpy)"
                          % what)


class Table(dict):
    """Columns of a CSV (name -> float array) with the file's '#' lines."""

    def __init__(self, columns=None, header=(), time=None):
        super().__init__(columns or {})
        self.header = list(header)
        self.time = time

    def __len__(self):
        return len(next(iter(self.values()))) if dict.__len__(self) else 0

    def n_rows(self):
        return len(self)


def _columns(names, rows):
    """name -> float array where every value is a number, else strings."""
    cols = {}
    for i, name in enumerate(names):
        values = [r[i] for r in rows]
        try:
            cols[name] = _array([float(v) for v in values])
        except (TypeError, ValueError):
            cols[name] = _array(values)
    return cols


def read_printed(source, pattern):
    """The numbers of femp's printed lines: every line of source (a file
    name, a text with line breaks, or a sequence of lines) that the
    regular expression pattern matches (re.search; anchor it with '^'
    where the line must start with it) gives one row. The columns are the
    pattern's named groups, or "1", "2", ... for its groups when it names
    none; a column whose values are all numbers is a float array, else an
    array of strings (a group that did not take part: ""). The Table's
    .lines holds the 0-based number of each row's line in the source, so
    rows of several patterns can be put back in their order."""
    if isinstance(source, str) and "\n" not in source:
        with open(source) as f:
            lines = f.read().split("\n")
    elif isinstance(source, str):
        lines = source.split("\n")
    else:
        lines = [l.rstrip("\n") for l in source]
    regex = re.compile(pattern)
    named = sorted(regex.groupindex.items(), key=lambda kv: kv[1])
    names = [k for k, _ in named] or [str(i + 1)
                                      for i in range(regex.groups)]
    index = [i for _, i in named] or list(range(1, regex.groups + 1))
    rows, where = [], []
    for k, line in enumerate(lines):
        m = regex.search(line)
        if m:
            rows.append([m.group(i) if m.group(i) is not None else ""
                         for i in index])
            where.append(k)
    t = Table(_columns(names, rows))
    t.lines = _array(where, int)
    return t


def read_parameters(path):
    """A parameter file (a scene, or the parameters.prm femp writes into
    its output directory): "Section/Subsection/Name" -> the value's text,
    comments and surrounding blanks removed. An entry set twice keeps the
    last value; 'include' lines are not followed."""
    values, section = {}, []
    with open(path) as f:
        for line in f:
            s = line.split("#")[0].strip()
            if s.startswith("subsection "):
                section.append(s[len("subsection "):].strip())
            elif s == "end":
                if section:
                    section.pop()
            else:
                m = re.match(r"set\s+(.*?)\s*=\s*(.*)$", s)
                if m:
                    values["/".join(section + [m.group(1)])] = \
                        m.group(2).strip()
    return values


def read_csv(path):
    """A femp CSV file: '#' comment lines, a header row, numeric rows.
    Non-numeric columns (e.g. 'section' of track_shape) stay strings."""
    header, rows = [], []
    with open(path) as f:
        for line in f:
            if line.startswith("#"):
                header.append(line[1:].strip())
            elif line.strip():
                rows.append(line.rstrip("\n").split(","))
    if not rows:
        raise ValueError("femp_post: %s has no header row" % path)
    names = [h.strip() for h in rows[0]]
    cols = _columns(names, [[v.strip() for v in r] for r in rows[1:]])
    time = None
    for h in header:
        m = re.match(r"time\s*=\s*([-+0-9.eE]+)", h)
        if m:
            time = float(m.group(1))
    return Table(cols, header, time)


class Fields(dict):
    """One field output: name -> array of one value per cell (grid) or per
    point (points), with .time (s), .n (the output number) and .centres
    (grid: cell centres, C x dim) or .positions (points: N x dim)."""

    def __init__(self, columns, time, n, coordinates, kind):
        super().__init__(columns)
        self.time = time
        self.n = n
        if kind == "grid":
            self.centres = coordinates
        else:
            self.positions = coordinates


# ------------------------------------------------------------- VTU pieces
def _decode_vtu_array(text, vtype, compressed, h="I"):
    """One inline base64 binary DataArray (UInt32 headers, h = "I", as
    deal.II writes them; "Q" for UInt64), zlib-compressed or not."""
    text = "".join(text.split())
    dtype = {"Float32": "<f4", "Float64": "<f8", "Int32": "<i4",
             "UInt32": "<u4", "Int64": "<i8", "UInt64": "<u8",
             "UInt8": "u1", "Int8": "i1"}[vtype]
    w = struct.calcsize("<" + h)
    if not compressed:
        raw = base64.b64decode(text)
        size = struct.unpack("<" + h, raw[:w])[0]
        return np.frombuffer(raw[w:w + size], dtype=dtype)
    first = base64.b64decode(text[:4 * ((w + 2) // 3 + 1)])
    nblocks = struct.unpack("<" + h, first[:w])[0]
    hlen = w * (3 + nblocks)
    hb64 = 4 * ((hlen + 2) // 3)
    header = struct.unpack("<%d%s" % (3 + nblocks, h),
                           base64.b64decode(text[:hb64])[:hlen])
    data = base64.b64decode(text[hb64:])
    parts, pos = [], 0
    for size in header[3:]:
        parts.append(zlib.decompress(data[pos:pos + size]))
        pos += size
    return np.frombuffer(b"".join(parts), dtype=dtype)


def read_vtu(path):
    """Points (N x 3), point-data arrays (name -> array, N or N x k), and
    the cell offsets of one VTU piece."""
    _need_numpy("reading a VTU file")
    text = open(path).read()
    compressed = "vtkZLibDataCompressor" in text[:400]
    h = "Q" if 'header_type="UInt64"' in text[:400] else "I"
    arrays, offsets, points = {}, None, None
    section = None
    for m in re.finditer(r"<(PointData|CellData|Points|Cells)\b|"
                         r"<DataArray([^>]*)>([^<]*)</DataArray>", text):
        if m.group(1):
            section = m.group(1)
            continue
        attrs = m.group(2)
        if 'format="binary"' not in attrs:
            continue
        vtype = re.search(r'type="(\w+)"', attrs).group(1)
        name = re.search(r'Name="([^"]+)"', attrs)
        ncomp = re.search(r'NumberOfComponents="(\d+)"', attrs)
        a = _decode_vtu_array(m.group(3), vtype, compressed, h)
        if ncomp and int(ncomp.group(1)) > 1:
            a = a.reshape(-1, int(ncomp.group(1)))
        if section == "Points":
            points = a.reshape(-1, 3)
        elif section == "Cells":
            if name and name.group(1) == "offsets":
                offsets = a
        elif section == "PointData" and name:
            arrays[name.group(1)] = a
    return points, arrays, offsets


def _pieces(directory, pvtu):
    """The VTU pieces a PVTU record names."""
    text = open(os.path.join(directory, pvtu)).read()
    return [os.path.join(directory, s)
            for s in re.findall(r'<Piece\s+Source="([^"]+)"', text)]


# ------------------------------------------------------------------- Run
class Run:
    """The output directory of one femp run (Output/Directory)."""

    def __init__(self, directory):
        self.dir = directory
        if not os.path.isdir(directory):
            raise FileNotFoundError("femp_post: no directory '%s'"
                                    % directory)
        if os.path.exists(self.path("grid.xdmf")) and not os.path.exists(
                self.path("grid.pvd")):
            self.format = "hdf5"
        else:
            self.format = "vtu"

    def path(self, name):
        return os.path.join(self.dir, name)

    # CSV series
    def melt_pool(self):
        """melt_pool.csv: time, length, width, depth (m), volume (m^3),
        T_max (K), solidus width and depth (m), every Time series
        interval."""
        return read_csv(self.path("melt_pool.csv"))

    def probe_points(self):
        return read_csv(self.path("probe_points.csv"))

    def absorption(self):
        return read_csv(self.path("absorption.csv"))

    def track_bead(self):
        return read_csv(self.path("track_bead.csv"))

    # the solid (Physics/Solid stress)
    def solid_energy(self, name="solid_energy.csv"):
        """Solid/Energy file: per solid step (or Solid/Row interval) the
        time, the works and energies (J) and the booked exchanges, the
        balance, mass_scaling and kinetic_to_elastic (doc/solid.md,
        "Energies and mass scaling")."""
        return read_csv(self.path(name))

    def solid_probes(self, name="solid_probes.csv"):
        """Solid/Probe file: sigma_xx and T at the Solid/Probe points."""
        return read_csv(self.path(name))

    # the parameters the run was made with
    def parameters(self):
        """parameters.prm of the output directory (every entry femp read,
        with its value): "Section/Name" -> text."""
        return read_parameters(self.path("parameters.prm"))

    def parameter(self, name):
        """The text of one entry of parameters.prm: name is the full
        "Section/Name", or the entry's name alone, which takes the first
        entry of that name in the file's order."""
        values = self.parameters()
        if name in values:
            return values[name]
        for key, value in values.items():
            if key.rsplit("/", 1)[-1] == name:
                return value
        raise KeyError("femp_post: no entry '%s' in %s"
                       % (name, self.path("parameters.prm")))

    # Builds (doc/builds.md)
    def porosity(self):
        """porosity.csv: per field output the pores' count, gas and powder
        volume (m^3), the built metal and the relative density."""
        return read_csv(self.path("porosity.csv"))

    def pores(self, n=None):
        """pores.csv: one row per pore (volume, powder, equivalent
        diameter, centroid x, y[, z]) of field output n (None: every
        output; n < 0 counts from the last output with a row)."""
        t = read_csv(self.path("pores.csv"))
        if n is None or not len(t.get("output", [])):
            return t
        outputs = sorted(set(int(x) for x in t["output"]))
        if n < 0:
            n = outputs[n] if -n <= len(outputs) else -1
        keep = [int(x) == n for x in t["output"]]
        return Table({k: _array([x for x, y in zip(v.tolist(), keep) if y])
                      for k, v in t.items()}, t.header, t.time)

    def tracks(self):
        """tracks.csv: per measured track its layer, times, bead height,
        width, re-melt depth and overlap (m)."""
        return read_csv(self.path("tracks.csv"))

    def layers(self):
        """layers.csv: per finished layer the means over its tracks."""
        return read_csv(self.path("layers.csv"))

    def layer_cost(self):
        """layer_cost.csv: per finished layer its window (s), steps, points
        and finite elements, and rank 0's wall time (s) in total and per
        part of the step (wall_solid, wall_melt_flow, ...)."""
        return read_csv(self.path("layer_cost.csv"))

    def _numbers(self, pattern):
        out = []
        for f in glob.glob(self.path(pattern.replace("%05d", "[0-9]" * 5))):
            m = re.search(r"_(\d{5})\.[a-z]+$", f)
            if m:
                out.append(int(m.group(1)))
        return sorted(out)

    def _pick(self, numbers, n, what):
        if not numbers:
            raise FileNotFoundError("femp_post: no %s in '%s'"
                                    % (what, self.dir))
        if n is None:
            return numbers[-1]
        if n < 0:
            return numbers[n]
        return n

    def probe_line_names(self):
        names = set()
        for f in glob.glob(self.path("probe_line_*_[0-9]*.csv")):
            m = re.match(r"probe_line_(.+)_\d{5}\.csv$", os.path.basename(f))
            if m:
                names.add(m.group(1))
        return sorted(names)

    def probe_line_numbers(self, name):
        return self._numbers("probe_line_%s_%%05d.csv" % name)

    def probe_line(self, name, n=None):
        """probe_line_<name>_<n>.csv: s (distance along the line), x, y,
        (z), and the sampled fields; .time is the output's time."""
        n = self._pick(self.probe_line_numbers(name), n,
                       "probe line '%s'" % name)
        t = read_csv(self.path("probe_line_%s_%05d.csv" % (name, n)))
        t.n = n
        return t

    def probe_line_summary(self, name, n=None, alpha_min=0.5,
                           fields=("sigma_xx", "von_mises")):
        """probe_line_summary() of probe_line(name, n)."""
        return probe_line_summary(self.probe_line(name, n), alpha_min, fields)

    def track_shape(self, n=None):
        n = self._pick(self._numbers("track_shape_%05d.csv"), n,
                       "track_shape_<n>.csv")
        t = read_csv(self.path("track_shape_%05d.csv" % n))
        t.n = n
        return t

    # field output
    def outputs(self, kind="grid"):
        """[(n, time)] of the field outputs of 'grid' or 'points', in
        order, from the index (grid.pvd or grid.xdmf)."""
        if self.format == "vtu":
            index = self.path(kind + ".pvd")
            if not os.path.exists(index):
                return []
            out = []
            for ds in ET.parse(index).getroot().iter("DataSet"):
                m = re.search(r"_(\d{5})\.pvtu$", ds.get("file"))
                out.append((int(m.group(1)), float(ds.get("timestep"))))
            return out
        return [(n, t) for n, t, _ in self._xdmf(kind)]

    def _xdmf(self, kind):
        index = self.path(kind + ".xdmf")
        if not os.path.exists(index):
            return []
        out = []
        for g in ET.parse(index).getroot().iter("Grid"):
            time = g.find("Time")
            if time is None:
                continue
            items = {}
            for item in g.iter("DataItem"):
                f, _, dset = item.text.strip().partition(":/")
                items[dset] = os.path.join(self.dir, f)
            fields = {}
            for a in g.iter("Attribute"):
                f, _, dset = a.find("DataItem").text.strip().partition(":/")
                fields[a.get("Name")] = (os.path.join(self.dir, f), dset)
            geometry = g.find("Geometry").find("DataItem").text.strip()
            topology = g.find("Topology").find("DataItem")
            m = re.search(r"_(\d{5})\.h5$", next(iter(fields.values()))[0]
                          if fields else geometry.partition(":/")[0])
            out.append((int(m.group(1)) if m else len(out),
                        float(time.get("Value")),
                        {"geometry": geometry.partition(":/"),
                         "topology": (topology.text.strip().partition(":/")
                                      if topology is not None else None),
                         "fields": fields}))
        return out

    def _time_of(self, kind, n):
        for m, t in self.outputs(kind):
            if m == n:
                return t
        return None

    def grid(self, n=None):
        """Grid output n: Fields with one value per cell and .centres."""
        _need_numpy("the grid output")
        numbers = [m for m, _ in self.outputs("grid")]
        n = self._pick(numbers, n, "grid output")
        if self.format == "hdf5":
            return self._grid_hdf5(n)
        centres, cols = [], {}
        for piece in _pieces(self.dir, "grid_%05d.pvtu" % n):
            pts, arrays, offsets = read_vtu(piece)
            corners = int(offsets[0]) if offsets is not None else 8
            dim = 3 if corners == 8 else 2
            c = pts.reshape(-1, corners, 3)[:, :, :dim].mean(axis=1)
            centres.append(c)
            for k, a in arrays.items():
                cols.setdefault(k, []).append(
                    a.reshape(len(c), corners, *a.shape[1:]).mean(axis=1))
        return Fields({k: np.concatenate(v) for k, v in cols.items()},
                      self._time_of("grid", n), n, np.concatenate(centres),
                      "grid")

    def _grid_hdf5(self, n):
        import h5py
        entry = [e for e in self._xdmf("grid") if e[0] == n][0]
        info = entry[2]
        mesh_file = os.path.join(self.dir, info["geometry"][0]) \
            if not os.path.isabs(info["geometry"][0]) else info["geometry"][0]
        with h5py.File(mesh_file, "r") as f:
            nodes = f[info["geometry"][2]][:]
            cells = f[info["topology"][2]][:]
        centres = nodes[cells.astype(np.int64)].mean(axis=1)
        cols = {}
        for name, (file, dset) in info["fields"].items():
            with h5py.File(file, "r") as f:
                cols[name] = f[dset][:].reshape(len(centres), -1).squeeze(1) \
                    if f[dset].ndim == 2 and f[dset].shape[1] == 1 \
                    else f[dset][:]
        return Fields(cols, entry[1], n, centres, "grid")

    def points(self, n=None):
        """Points output n (where written): Fields with one value per
        point and .positions (N x dim)."""
        _need_numpy("the points output")
        numbers = [m for m, _ in self.outputs("points")]
        n = self._pick(numbers, n, "points output")
        if self.format == "hdf5":
            import h5py
            entry = [e for e in self._xdmf("points") if e[0] == n][0]
            info = entry[2]
            cols = {}
            file = os.path.join(self.dir, info["geometry"][0])
            with h5py.File(file, "r") as f:
                pos = f[info["geometry"][2]][:]
            for name, (file, dset) in info["fields"].items():
                with h5py.File(file, "r") as f:
                    a = f[dset][:]
                cols[name] = a[:, 0] if a.ndim == 2 and a.shape[1] == 1 else a
            return Fields(cols, entry[1], n, pos, "points")
        pos, cols = [], {}
        for piece in _pieces(self.dir, "points_%05d.pvtu" % n):
            pts, arrays, _ = read_vtu(piece)
            pos.append(pts)
            for k, a in arrays.items():
                cols.setdefault(k, []).append(a)
        pos = np.concatenate(pos) if pos else np.zeros((0, 3))
        return Fields({k: np.concatenate(v) for k, v in cols.items()},
                      self._time_of("points", n), n, pos, "points")


def probe_line_summary(line, alpha_min=0.5,
                       fields=("sigma_xx", "von_mises")):
    """A reading of a probe line (a Table of probe_line_<name>_<n>.csv,
    with its 'alpha' column) that does not hang on partly filled cells:
    a cell's stress is the mean over its few solid points, which in a cell
    that is mostly gas or powder changes from one realization of a build to
    the next. Returns 'samples' (all), 'stressed' (the samples of nonzero
    von Mises stress: solid metal; gas, powder and melt carry none),
    'metal' (the stressed samples in cells with alpha >= alpha_min),
    'partial' (the stressed samples with alpha < alpha_min) and, per
    field, mean, min and max over the 'metal' samples (None where there
    are none)."""
    alpha = [float(a) for a in line["alpha"]]
    stressed = [i for i, v in enumerate(line["von_mises"]) if float(v) != 0]
    keep = [i for i in stressed if alpha[i] >= alpha_min]
    out = {"samples": len(alpha), "stressed": len(stressed),
           "metal": len(keep), "partial": len(stressed) - len(keep)}
    for f in fields:
        v = [float(line[f][i]) for i in keep]
        out[f] = ({"mean": sum(v) / len(v), "min": min(v), "max": max(v)}
                  if v else None)
    return out


def pore_neighbourhood_summary(grid, mask=None, alpha_min=0.5,
                               fields=("sigma_xx", "sigma_yy", "sigma_zz",
                                       "von_mises"),
                               far=2, within=None):
    """The stress in the metal around the cells of @p mask (a boolean per
    cell of a grid output on a uniform grid; None: the pore cells, field
    'pore' > 0) against the metal away from them. The metal cells are the
    stressed ones (von Mises != 0) with alpha >= alpha_min outside the
    mask. 'next': those that share a face with a mask cell; 'away': those
    more than @p far cells from every mask cell (the largest of the index
    distances in x, y, z), and inside @p within (a boolean per cell, e.g.
    the built region; None: everywhere). Returns the counts 'mask',
    'metal', 'next', 'away', the cell numbers 'next_cells' and
    'away_cells', and per field {'next': ..., 'away': ...}, each mean,
    min and max (None where there are none)."""
    _need_numpy("pore_neighbourhood_summary()")
    c = np.asarray(grid.centres, dtype=float)
    lo = c.min(axis=0)
    h = min(np.diff(np.unique(np.round(c[:, d], 12))).min()
            for d in range(c.shape[1]) if len(np.unique(c[:, d])) > 1)
    ijk = np.rint((c - lo) / h).astype(np.int64)
    if np.abs((c - lo) / h - ijk).max() > 1e-3:  # float32 VTU points
        raise ValueError("femp_post: pore_neighbourhood_summary() needs "
                         "the cells of a uniform grid")
    if mask is None:
        mask = np.asarray(grid["pore"]) > 0
    mask = np.asarray(mask, dtype=bool)
    within = (np.ones(len(c), dtype=bool) if within is None
              else np.asarray(within, dtype=bool))
    shape = ijk.max(axis=0) + 1
    box = np.zeros(shape, dtype=bool)
    box[tuple(ijk[mask].T)] = True
    # the face neighbours of the mask cells; the cells within `far` of one
    # (grown along each axis in turn: a cube of side 2 far + 1)
    touch = np.zeros(shape, dtype=bool)
    for d in range(len(shape)):
        for step in (-1, 1):
            touch |= np.roll(box, step, axis=d) & _no_wrap(shape, d, step)
    near = box.copy()
    for d in range(len(shape)):
        for _ in range(far):
            grown = near.copy()
            for step in (-1, 1):
                grown |= (np.roll(near, step, axis=d)
                          & _no_wrap(shape, d, step))
            near = grown
    metal = ((np.asarray(grid["von_mises"]) != 0)
             & (np.asarray(grid["alpha"]) >= alpha_min) & ~mask)
    at = tuple(ijk.T)
    nxt = np.flatnonzero(metal & touch[at])
    away = np.flatnonzero(metal & ~near[at] & within)
    out = {"mask": int(mask.sum()), "metal": int(metal.sum()),
           "next": len(nxt), "away": len(away),
           "next_cells": nxt, "away_cells": away}
    for f in fields:
        v = np.asarray(grid[f], dtype=float)
        out[f] = {}
        for name, cells in (("next", nxt), ("away", away)):
            out[f][name] = ({"mean": float(v[cells].mean()),
                             "min": float(v[cells].min()),
                             "max": float(v[cells].max())}
                            if len(cells) else None)
    return out


def _no_wrap(shape, axis, step):
    """Mask of the cells that np.roll(..., step, axis) filled from a real
    neighbour (not wrapped round from the other end)."""
    keep = np.ones(shape, dtype=bool)
    index = [slice(None)] * len(shape)
    index[axis] = 0 if step > 0 else -1
    keep[tuple(index)] = False
    return keep


def von_mises(f):
    """von Mises stress (Pa) of a points' Fields from stress_xx ... _yz."""
    s = {k: f["stress_" + k] for k in ("xx", "yy", "zz", "xy", "xz", "yz")
         if "stress_" + k in f}
    return np.sqrt(0.5 * ((s["xx"] - s["yy"]) ** 2 + (s["yy"] - s["zz"]) ** 2
                          + (s["zz"] - s["xx"]) ** 2)
                   + 3 * (s.get("xy", 0) ** 2 + s.get("xz", 0) ** 2
                          + s.get("yz", 0) ** 2))
