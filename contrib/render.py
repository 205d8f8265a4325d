# femp: 3D pictures of a track from a run's output, drawn by ParaView
# without a display (the paper's Figs. 7 and 9: the track's surface coloured
# by temperature and by von Mises stress). Run with ParaView's batch
# interpreter (Debian 12: apt-get install paraview python3-paraview xvfb):
#
#   xvfb-run -a pvbatch contrib/render.py [options] RUN [RUN ...]
#
# RUN is an output directory (Output/Directory of the scene), optionally as
# DIR=LABEL; several runs are drawn side by side in one picture per view and
# time, with one colour range (e.g. the three laser powers of Fig. 9). Both
# output formats are read: grid.pvd / points.pvd (Output/Format = vtu) and
# grid.xdmf / points.xdmf (Output/Format = hdf5).
#
# Views (--views, comma-separated; default all four):
#   T          the metal (grid cells with alpha >= 1/2, the metal fraction)
#              as a solid, its surface coloured by the temperature T (K);
#              with --surface points the metal material points instead;
#   von_mises  the FE zone (the grid cells below the lowest material point
#              with a stress: the points inside the FE zone carry none) by
#              the elements' von_mises, and the metal points above it (von
#              Mises stress from their stress tensor) together, in MPa;
#              without points at that time: the metal cells' von_mises;
#   cut_T      the metal cut along the track (the plane y = --cut-y, the
#              half y < cut removed) coloured by T, with the melt pool's
#              outline (liquid fraction gamma = 1/2) on the cut;
#   cut_von_mises  the same cut coloured by the cells' von Mises stress;
#   cut_pores  the metal cut across the tracks (the plane x = --cut-x, the
#              half x < cut removed) coloured by the cells' unfused powder
#              share (the field unfused_powder: 0 fused metal, 1 powder that
#              never melted), with the pores (cells of the field pore > 0,
#              enclosed gas: doc/builds.md) behind the cut drawn in magenta;
#              --cut-x pore puts the cut through the largest pore of that
#              output (pores.csv). Needs a scene with pore detection
#              (Porosity/Detect pores, on with a layer schedule).
# Times (--times): 'last' (default), 'all', or comma-separated times in s;
# each is matched to the nearest grid output (the points are drawn only
# when they were written at that time: Output/Write material points =
# always). Files: OUT/PREFIX<view>_<time in us>us.png.
#
# --palette writes 256-colour PNGs (python3-pil), about a third of the size.
# --state FILE.pvsm also writes a ParaView state of the first view at the
# first time, for turning the view by hand: paraview --state=FILE.pvsm.
#
# Writing the grid and the points at chosen times, e.g. for the default
# scene every 10 us with the points:
#   mpirun -np 2 build/femp --set "Output/Output interval=1e-5" \
#     --set "Output/Write material points=always" prm/case_3_2_reduced.prm
# doc/output.md describes the files; doc/tutorials/render.md the pictures.
import argparse
import builtins  # the programmable filter shadows max, min, ... in __main__
import math
import os
import sys

from paraview.simple import *  # noqa: F401,F403 (ParaView's own API)
from paraview import servermanager as sm


def parse_args(argv):
    p = argparse.ArgumentParser(
        description="3D pictures of a femp track (pvbatch).")
    p.add_argument("runs", nargs="+", help="output directory[=label]")
    p.add_argument("--views", default="T,von_mises,cut_T,cut_von_mises",
                   help="comma-separated: T, von_mises, cut_T, "
                        "cut_von_mises, cut_pores")
    p.add_argument("--times", default="last",
                   help="'last', 'all' or comma-separated times in s")
    p.add_argument("--out", default=".", help="directory of the PNG files")
    p.add_argument("--prefix", default="track_", help="file name prefix")
    p.add_argument("--size", default="1200x800",
                   help="picture size of one run's panel, pixels WxH")
    p.add_argument("--surface", choices=["grid", "points"], default="grid",
                   help="the T view's metal: grid cells or material points")
    p.add_argument("--point-radius", type=float, default=None,
                   help="radius of the points' spheres, m (default: a "
                        "quarter of the grid's cell size)")
    p.add_argument("--cut-y", type=float, default=None,
                   help="y of the cut plane, m (default: the domain's middle)")
    p.add_argument("--cut-x", default=None,
                   help="x of the cut_pores plane, m, or 'pore' (through "
                        "the largest pore; default: the domain's middle)")
    p.add_argument("--T-range", default=None,
                   help="colour range of T, K, as MIN,MAX (default: data)")
    p.add_argument("--vm-range", default=None,
                   help="colour range of von Mises, MPa, MIN,MAX")
    p.add_argument("--state", default=None,
                   help="also write a ParaView state file (.pvsm)")
    p.add_argument("--palette", action="store_true",
                   help="write 256-colour PNGs (python3-pil): about a third "
                        "of the size, for pictures kept in a repository")
    p.add_argument("--check", action="store_true",
                   help="fail unless every picture has at least 2 %% of "
                        "its pixels drawn (not background)")
    return p.parse_args(argv)


# ---------------------------------------------------------------- reading
def times_of(reader):
    tv = reader.TimestepValues
    if tv is None:
        return [0.0]
    try:
        return [float(x) for x in tv]
    except TypeError:
        return [float(tv)]


def open_series(directory, name):
    """Reader of DIR/name.pvd or DIR/name.xdmf; None when neither exists."""
    pvd = os.path.join(directory, name + ".pvd")
    xdmf = os.path.join(directory, name + ".xdmf")
    if os.path.exists(pvd):
        return PVDReader(FileName=os.path.abspath(pvd)), "vtu"
    if os.path.exists(xdmf):
        return XDMFReader(FileNames=[os.path.abspath(xdmf)]), "hdf5"
    return None, None


def as_dataset(proxy, time):
    """The VTK data set of a pipeline object at a time (first block of a
    multiblock)."""
    proxy.UpdatePipeline(time)
    d = sm.Fetch(proxy)
    if d is not None and d.IsA("vtkMultiBlockDataSet"):
        it = d.NewIterator()
        it.InitTraversal()
        d = it.GetCurrentDataObject() if not it.IsDoneWithTraversal() else None
    return d


class Run:
    """One run's output: its grid pipeline (cell fields turned into point
    fields on merged nodes), and its points where written."""

    def __init__(self, spec):
        # DIR or DIR=LABEL (a directory name may itself hold '=').
        directory, label = spec, ""
        if not os.path.isdir(spec) and "=" in spec:
            directory, _, label = spec.rpartition("=")
        self.dir = directory
        self.label = label or os.path.basename(os.path.normpath(directory))
        grid, self.format = open_series(directory, "grid")
        if grid is None:
            sys.exit("render.py: no grid.pvd or grid.xdmf in '%s' (the "
                     "run's Output/Directory)" % directory)
        self.grid_reader = grid
        self.grid_times = times_of(grid)
        self.points_reader, _ = open_series(directory, "points")
        self.points_times = (times_of(self.points_reader)
                             if self.points_reader else [])
        cells = grid
        if self.format == "vtu":
            # deal.II writes each cell as a patch with its own corners, the
            # cell's value at each: one value per cell first.
            cells = PointDatatoCellData(Input=grid)
            cells.PassPointData = 0
        merged = CleantoGrid(Input=cells)  # merge the cells' shared nodes
        self.cells = merged
        nodal = CellDatatoPointData(Input=merged)
        nodal.PassCellData = 1
        # A dummy array as the active scalars: the scalar clip below drops
        # the active scalars, which the XDMF reader makes T.
        nodal = Calculator(Input=nodal)
        nodal.AttributeType = "Point Data"
        nodal.ResultArrayName = "active_dummy"
        nodal.Function = "0"
        self.nodal = nodal
        # The metal as a solid: the region alpha >= 1/2 of the nodal
        # metal fraction.
        metal = Clip(Input=nodal)
        metal.ClipType = "Scalar"
        metal.Scalars = ["POINTS", "alpha"]
        metal.Value = 0.5
        metal.Invert = 0
        self.metal = metal
        d = as_dataset(merged, self.grid_times[-1])
        b = d.GetBounds()
        self.bounds = b
        volume = (b[1] - b[0]) * (b[3] - b[2]) * builtins.max(b[5] - b[4], 1e-300)
        self.cell_size = (volume / builtins.max(1, d.GetNumberOfCells())) ** (1 / 3)

    def grid_time(self, wanted):
        return builtins.min(self.grid_times, key=lambda t: builtins.abs(t - wanted))

    def has_points_at(self, t):
        if not self.points_times:
            return False
        tol = 1e-3 * builtins.max(1e-12, (self.grid_times[-1] - self.grid_times[0])
                         / builtins.max(1, len(self.grid_times) - 1))
        return builtins.min(builtins.abs(tp - t) for tp in self.points_times) <= tol


# ---------------------------------------------------------------- drawing
def apply_map(lut, preset):
    for name in (preset, "Turbo", "Jet", "Rainbow Uniform"):
        try:
            if lut.ApplyPreset(name, True):
                return
        except Exception:
            pass


def colour(display, view, association, array, lut_name, title, rng,
           fmt="%.0f"):
    ColorBy(display, (association, array))
    lut = GetColorTransferFunction(lut_name)
    apply_map(lut, "Turbo")
    lut.RescaleTransferFunction(rng[0], rng[1])
    lut.AutomaticRescaleRangeMode = "Never"
    GetOpacityTransferFunction(lut_name).RescaleTransferFunction(*rng)
    display.SetScalarBarVisibility(view, True)
    bar = GetScalarBar(lut, view)
    bar.Title = title
    bar.ComponentTitle = ""
    bar.TitleColor = bar.LabelColor = [0, 0, 0]
    bar.TitleFontSize = 16
    bar.LabelFontSize = 14
    bar.ScalarBarLength = 0.5
    bar.HorizontalTitle = 1
    bar.WindowLocation = "Any Location"
    bar.Position = [0.87, 0.15]
    bar.AutomaticLabelFormat = 0
    bar.LabelFormat = fmt
    bar.RangeLabelFormat = fmt
    return lut


VM_SCRIPT = """
import numpy as np
from vtkmodules.numpy_interface import dataset_adapter as dsa
from vtkmodules.util.numpy_support import numpy_to_vtk, numpy_to_vtkIdTypeArray
from vtkmodules.vtkCommonDataModel import vtkCellArray
from vtkmodules.vtkCommonCore import vtkPoints
d = self.GetInputDataObject(0, 0)
if d.IsA("vtkMultiBlockDataSet"):
    it = d.NewIterator(); it.InitTraversal(); d = it.GetCurrentDataObject()
w = dsa.WrapDataObject(d)
pd = w.PointData
keep = (np.asarray(pd["state"]) > 0.5) & (np.asarray(w.Points)[:, 2] >= Z_FE)
s = {k: np.asarray(pd["stress_" + k])[keep]
     for k in ("xx", "yy", "zz", "xy", "xz", "yz")}
vm = 1e-6 * np.sqrt(0.5 * ((s["xx"] - s["yy"]) ** 2 + (s["yy"] - s["zz"]) ** 2
                           + (s["zz"] - s["xx"]) ** 2)
                    + 3 * (s["xy"] ** 2 + s["xz"] ** 2 + s["yz"] ** 2))
xyz = np.ascontiguousarray(np.asarray(w.Points)[keep], dtype=np.float64)
out = self.GetPolyDataOutput()
pts = vtkPoints()
pts.SetData(numpy_to_vtk(xyz, deep=1))
out.SetPoints(pts)
n = len(xyz)
conn = np.empty(2 * n, dtype=np.int64)
conn[0::2] = 1
conn[1::2] = np.arange(n)
cells = vtkCellArray()
cells.SetCells(n, numpy_to_vtkIdTypeArray(conn, deep=1))
out.SetVerts(cells)
a = numpy_to_vtk(np.ascontiguousarray(vm), deep=1)
a.SetName("von_mises_MPa")
out.GetPointData().AddArray(a)
"""


def von_mises_points(points, z_fe=-1e300):
    """Metal points (state 1 solid, 2 fluid) above z_fe (the FE zone's top)
    with their von Mises stress in MPa from the stress tensor (a
    programmable filter: ParaView 5.11's Threshold crashed on the
    points)."""
    f = ProgrammableFilter(Input=points)
    f.OutputDataSetType = "vtkPolyData"
    f.Script = "Z_FE = %r\n" % z_fe + VM_SCRIPT
    return f


def fe_zone_top(run, t):
    """Top of the FE zone, m: the points inside the FE zone carry no
    stress (the elements do), so the lowest point with a stress, down to
    the cell face below it."""
    from vtkmodules.util.numpy_support import vtk_to_numpy
    d = as_dataset(run.points_reader, t)
    pd = d.GetPointData()
    z = vtk_to_numpy(d.GetPoints().GetData())[:, 2]
    stressed = None
    for k in ("xx", "yy", "zz", "xy", "xz", "yz"):
        a = pd.GetArray("stress_" + k)
        if a is None:
            return run.bounds[4]
        nz = vtk_to_numpy(a) != 0
        stressed = nz if stressed is None else stressed | nz
    if stressed is None or not stressed.any():
        return run.bounds[4]
    h = run.cell_size
    z0 = run.bounds[4]
    return z0 + math.floor((z[stressed].min() - z0) / h + 1e-6) * h


def mpa(src, association):
    c = Calculator(Input=src)
    c.AttributeType = "Cell Data" if association == "CELLS" else "Point Data"
    c.ResultArrayName = "von_mises_MPa"
    c.Function = "1e-6*von_mises"
    return c


def array_range(proxy, association, name, time):
    d = as_dataset(proxy, time)
    if d is None:
        return None
    data = d.GetCellData() if association == "CELLS" else d.GetPointData()
    a = data.GetArray(name)
    if a is None or a.GetNumberOfTuples() == 0:
        return None
    return a.GetRange()


def set_camera(view, b, cut):
    cx, cy, cz = (b[0] + b[1]) / 2, (b[2] + b[3]) / 2, (b[4] + b[5]) / 2
    L = builtins.max(b[1] - b[0], b[3] - b[2], b[5] - b[4])
    # From the front left, above: the track (along x) runs to the right;
    # a cut across the tracks (cut == "x") is seen from -x.
    d = (-0.55, -1.0, 0.75) if not cut else (-0.35, -1.0, 0.45)
    if cut == "x":
        d = (-1.0, 0.35, 0.45)
    n = math.sqrt(builtins.sum(x * x for x in d))
    view.CameraPosition = [cx + 2.6 * L * d[0] / n, cy + 2.6 * L * d[1] / n,
                           cz + 2.6 * L * d[2] / n]
    view.CameraFocalPoint = [cx, cy, cz]
    view.CameraViewUp = [0, 0, 1]
    view.CameraViewAngle = 30
    view.ResetCamera()
    view.CameraParallelProjection = 0
    cam = view.GetActiveCamera()
    cam.Dolly(1.3)
    # Room for the colour bar on the right: the model a little to the left.
    shift = [0.09 * L * x for x in (-d[1], d[0], 0)]
    view.CameraFocalPoint = [a + b for a, b in zip(view.CameraFocalPoint, shift)]
    view.CameraPosition = [a + b for a, b in zip(view.CameraPosition, shift)]


def new_view(size):
    v = CreateView("RenderView")
    v.ViewSize = size
    v.Background = [1, 1, 1]
    try:
        v.UseColorPaletteForBackground = 0
    except AttributeError:
        pass
    v.OrientationAxesVisibility = 1
    v.OrientationAxesLabelColor = [0, 0, 0]
    return v


def label(view, run, where="Upper Left Corner"):
    """The run's label and the time shown (it follows the time when the
    view is turned in ParaView from a saved state)."""
    t = AnnotateTimeFilter(Input=run.grid_reader)
    t.Format = run.label.replace("{", "{{").replace("}", "}}") + \
        "   t = {time:.4g} us"
    t.Scale = 1e6
    d = Show(t, view)
    d.Color = [0, 0, 0]
    d.FontSize = 18
    d.WindowLocation = where


def spheres(display, run, args):
    """Material points drawn as spheres of radius --point-radius (default:
    a quarter of the grid's cell size: the points' half-spacing with two
    points per cell and direction)."""
    display.SetRepresentationType("Point Gaussian")
    display.ShaderPreset = "Sphere"
    display.GaussianRadius = args.point_radius or 0.25 * run.cell_size


def draw(run, kind, t, view, args, rng):
    """Put the pipeline of one view kind of one run at time t into view."""
    scene = GetAnimationScene()  # the time a saved state opens at
    scene.UpdateAnimationUsingDataTimeSteps()
    scene.AnimationTime = t
    view.ViewTime = t
    cut = kind.startswith("cut_")
    field = "T" if kind.endswith("T") else "vm"
    b = run.bounds
    metal = run.metal
    if kind == "cut_pores":
        draw_pores(run, t, view, args)
        label(view, run)
        set_camera(view, b, "x")
        return
    if cut:
        y0 = args.cut_y if args.cut_y is not None else (b[2] + b[3]) / 2
        half = Clip(Input=run.metal)
        half.ClipType = "Plane"
        half.ClipType.Origin = [0, y0, 0]
        half.ClipType.Normal = [0, 1, 0]
        half.Invert = 0  # keep y >= y0: the cut faces the camera
        metal = half
    if kind == "T" and args.surface == "points" and run.has_points_at(t):
        d = Show(run.points_reader, view)
        spheres(d, run, args)
        colour(d, view, "POINTS", "temperature", "temperature", "T (K)",
               rng["T"])
    elif field == "T":
        s = ExtractSurface(Input=metal)
        d = Show(s, view)
        colour(d, view, "POINTS", "T", "T", "T (K)", rng["T"])
    elif kind == "von_mises" and run.has_points_at(t):
        z_fe = fe_zone_top(run, t)
        fe = Clip(Input=run.cells)
        fe.ClipType = "Plane"
        fe.ClipType.Origin = [0, 0, z_fe - 1e-3 * run.cell_size]
        fe.ClipType.Normal = [0, 0, 1]
        fe.Invert = 1  # below the lowest point
        fe.Crinkleclip = 1
        fe_vm = mpa(fe, "CELLS")
        d = Show(fe_vm, view)
        colour(d, view, "CELLS", "von_mises_MPa", "von_mises_MPa",
               "von Mises\n(MPa)", rng["vm"])
        pts = von_mises_points(run.points_reader, z_fe)
        dp = Show(pts, view)
        spheres(dp, run, args)
        colour(dp, view, "POINTS", "von_mises_MPa", "von_mises_MPa",
               "von Mises\n(MPa)", rng["vm"])
    else:
        s = mpa(ExtractSurface(Input=metal), "CELLS")
        d = Show(s, view)
        colour(d, view, "CELLS", "von_mises_MPa", "von_mises_MPa",
               "von Mises\n(MPa)", rng["vm"])
    if cut:
        # The melt pool's outline on the cut face.
        y0 = args.cut_y if args.cut_y is not None else (b[2] + b[3]) / 2
        sl = Slice(Input=run.nodal)
        sl.SliceType = "Plane"
        sl.SliceType.Origin = [0, y0 + 1e-9, 0]
        sl.SliceType.Normal = [0, 1, 0]
        pool = Contour(Input=sl, ContourBy=["POINTS", "gamma"],
                       Isosurfaces=[0.5])
        dl = Show(pool, view)
        dl.ColorArrayName = ["POINTS", ""]
        dl.AmbientColor = dl.DiffuseColor = [1, 1, 1]
        dl.LineWidth = 3
    label(view, run)
    set_camera(view, b, cut)


def largest_pore_x(run, t):
    """x of the centroid of the largest pore of the output at time t
    (pores.csv of the run, read by contrib/femp_post.py); None without
    pores."""
    sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
    import femp_post
    name = os.path.join(run.dir, "pores.csv")
    if not os.path.exists(name):
        return None
    pores = femp_post.read_csv(name)
    best = None
    for time, volume, x in zip(pores["time"].tolist(),
                               pores["volume"].tolist(), pores["x"].tolist()):
        if builtins.abs(time - t) > 1e-3 * builtins.max(t, 1e-12):
            continue
        if best is None or volume > best[0]:
            best = (volume, x)
    return best[1] if best else None


def draw_pores(run, t, view, args):
    """The cut_pores view: the metal cut at x = x0 coloured by the cells'
    unfused powder share, the pore cells beyond the cut in magenta."""
    b = run.bounds
    x0 = (b[0] + b[1]) / 2
    if args.cut_x == "pore":
        x = largest_pore_x(run, t)
        if x is None:
            print("render.py: no pore at t = %.4g s in %s: cut at the middle"
                  % (t, run.dir))
        else:
            x0 = x
    elif args.cut_x is not None:
        x0 = float(args.cut_x)
    if run.grid_reader.CellData.GetArray("unfused_powder") is None and \
            run.grid_reader.PointData.GetArray("unfused_powder") is None:
        sys.exit("render.py: cut_pores: '%s' has no field unfused_powder "
                 "(a scene with Porosity/Detect pores)" % run.dir)
    half = Clip(Input=run.metal)
    half.ClipType = "Plane"
    half.ClipType.Origin = [x0, 0, 0]
    half.ClipType.Normal = [1, 0, 0]
    half.Invert = 0  # keep x >= x0: the cut faces the camera
    s = ExtractSurface(Input=half)
    d = Show(s, view)
    lut = colour(d, view, "CELLS", "unfused_powder", "unfused_powder",
                 "unfused\npowder", [0, 1], "%.1f")
    apply_map(lut, "Cool to Warm")
    pores = Threshold(Input=run.cells)
    pores.Scalars = ["CELLS", "pore"]
    try:
        pores.LowerThreshold = 0.5
        pores.UpperThreshold = 1e30
        pores.ThresholdMethod = "Between"
    except AttributeError:  # ParaView before 5.10
        pores.ThresholdRange = [0.5, 1e30]
    beyond = Clip(Input=pores)
    beyond.ClipType = "Plane"
    beyond.ClipType.Origin = [x0 - 1e-3 * run.cell_size, 0, 0]
    beyond.ClipType.Normal = [1, 0, 0]
    beyond.Invert = 0
    beyond.Crinkleclip = 1
    dp = Show(beyond, view)
    dp.ColorArrayName = ["POINTS", ""]
    dp.AmbientColor = dp.DiffuseColor = [0.85, 0.0, 0.85]
    note = Text(Text="cut at x = %.0f um; pores in magenta" % (x0 * 1e6))
    dn = Show(note, view)
    dn.Color = [0, 0, 0]
    dn.FontSize = 16
    dn.WindowLocation = "Lower Right Corner"


def ranges(runs, kinds, t_of, args):
    """One colour range per field over all runs at their times."""
    out = {}
    def given(s):
        return [float(x) for x in s.split(",")] if s else None
    T = given(args.T_range)
    vm = given(args.vm_range)
    lo_T, hi_T, lo_vm, hi_vm = [], [], [], []
    for r in runs:
        t = t_of[r]
        if T is None:
            a = array_range(r.metal, "POINTS", "T", t)
            if a:
                lo_T.append(a[0]); hi_T.append(a[1])
        if vm is None and builtins.any(k.endswith("von_mises") for k in kinds):
            a = array_range(r.metal, "CELLS", "von_mises", t)
            if a:
                lo_vm.append(a[0] * 1e-6); hi_vm.append(a[1] * 1e-6)
            if r.has_points_at(t):
                a = array_range(von_mises_points(r.points_reader,
                                                 fe_zone_top(r, t)),
                                "POINTS", "von_mises_MPa", t)
                if a:
                    lo_vm.append(a[0]); hi_vm.append(a[1])
    out["T"] = T or ([builtins.min(lo_T), builtins.max(hi_T)] if lo_T else [300, 3000])
    out["vm"] = vm or ([0, builtins.max(hi_vm)] if hi_vm else [0, 1])
    if out["vm"][1] <= out["vm"][0]:
        out["vm"][1] = out["vm"][0] + 1
    return out


def main(argv):
    args = parse_args(argv)
    kinds = [k.strip() for k in args.views.split(",") if k.strip()]
    allowed = ("T", "von_mises", "cut_T", "cut_von_mises", "cut_pores")
    for k in kinds:
        if k not in allowed:
            sys.exit("render.py: --views: '%s' is not one of %s"
                     % (k, ", ".join(allowed)))
    w, h = (int(x) for x in args.size.lower().split("x"))
    first = Run(args.runs[0])
    if args.times == "last":
        wanted = [first.grid_times[-1]]
    elif args.times == "all":
        wanted = list(first.grid_times)
    else:
        wanted = [float(x) for x in args.times.split(",")]
    os.makedirs(args.out, exist_ok=True)
    written = []
    state_done = False
    for tw in wanted:
        # A fresh session for each picture: ParaView 5.11 crashed (in a
        # Threshold of the points) when one session went on to later times.
        ResetSession()
        runs = [Run(s) for s in args.runs]
        t_of = {r: r.grid_time(tw) for r in runs}
        rng = ranges(runs, kinds, t_of, args)
        times = [t_of[r] for r in runs]
        for kind in kinds:
            ResetSession()
            runs = [Run(s) for s in args.runs]
            t_of = dict(zip(runs, times))
            layout = CreateLayout("femp")
            # Equal panels side by side: split the frame on the right in
            # turn (the children of frame i are 2i+1, 2i+2).
            cells, cell = [], 0
            for i in range(len(runs) - 1):
                layout.SplitHorizontal(cell, 1.0 / (len(runs) - i))
                cells.append(2 * cell + 1)
                cell = 2 * cell + 2
            cells.append(cell)
            views = []
            for r, c in zip(runs, cells):
                v = new_view([w, h])
                AssignViewToLayout(view=v, layout=layout, hint=c)
                draw(r, kind, t_of[r], v, args, rng)
                views.append(v)
            for v in views[:-1]:  # one colour bar per picture
                for rep in v.Representations:
                    try:
                        rep.SetScalarBarVisibility(v, False)
                    except Exception:
                        pass
            name = os.path.join(args.out, "%s%s_%03dus.png"
                                % (args.prefix, kind,
                                   int(builtins.round(times[0] * 1e6))))
            SaveScreenshot(name, layout,
                           ImageResolution=[w * len(runs), h],
                           TransparentBackground=0)
            written.append(name)
            print("render.py: wrote %s (t = %.4g s)" % (name, times[0]))
            if args.state and not state_done:
                SaveState(args.state)
                print("render.py: wrote %s" % args.state)
                state_done = True
    for name in written:
        if not os.path.exists(name) or os.path.getsize(name) == 0:
            sys.exit("render.py: %s was not written" % name)
        if args.palette:
            to_palette(name)
        if args.check:
            f = drawn_fraction(name)
            print("render.py: %s: %.1f %% of the pixels drawn" % (name,
                                                                  100 * f))
            if f < 0.02:
                sys.exit("render.py: %s is blank" % name)


def to_palette(png):
    """Rewrite a PNG with a palette of 256 colours (octree quantization,
    no dithering)."""
    try:
        from PIL import Image
    except ImportError:
        sys.exit("render.py: --palette needs python3-pil")
    im = Image.open(png).convert("RGB")
    im.quantize(colors=256, method=Image.Quantize.FASTOCTREE,
                dither=Image.Dither.NONE).save(png, optimize=True)


def drawn_fraction(png):
    """Fraction of the pixels of a PNG that differ from the white
    background."""
    from vtkmodules.vtkIOImage import vtkPNGReader
    from vtkmodules.util.numpy_support import vtk_to_numpy
    r = vtkPNGReader()
    r.SetFileName(png)
    r.Update()
    a = vtk_to_numpy(r.GetOutput().GetPointData().GetScalars())
    rgb = a[:, :3].astype(int)
    return float((rgb.sum(axis=1) < 3 * 250).mean())


if __name__ == "__main__":
    main(sys.argv[1:])
