# femp: open femp's HDF5 + XDMF output (Output/Format = hdf5) in ParaView
# without a display and print, per XDMF file, its time steps and for each the
# number of cells and points and the range of T / temperature / alpha /
# sigma_xx. Run with ParaView's batch interpreter (Debian: apt-get install
# paraview python3-paraview):
#   pvbatch contrib/check_xdmf_paraview.py output/<scene>/grid.xdmf output/<scene>/points.xdmf
import sys
from paraview.simple import *
from paraview import servermanager as sm
for f in sys.argv[1:]:
    r = XDMFReader(FileNames=[f])
    tv = r.TimestepValues
    try:
        times = [float(x) for x in tv]
    except TypeError:
        times = [float(tv)]
    print(f, 'time steps:', len(times), [round(t*1e6,3) for t in times])
    for t in times:
        r.UpdatePipeline(t)
        d = sm.Fetch(r)
        # multiblock or dataset
        try:
            n = d.GetNumberOfCells(); p = d.GetNumberOfPoints()
        except AttributeError:
            it = d.NewIterator(); it.InitTraversal(); ds = it.GetCurrentDataObject(); n = ds.GetNumberOfCells(); p = ds.GetNumberOfPoints(); d = ds
        arrs=[]
        cd = d.GetCellData(); pd = d.GetPointData()
        for data in (cd, pd):
            for i in range(data.GetNumberOfArrays()):
                a = data.GetArray(i)
                if a.GetName() in ('T','temperature','alpha','sigma_xx'):
                    arrs.append('%s[%.4g,%.4g]' % (a.GetName(), *a.GetRange()))
        print('  t=%.3g us cells %d points %d %s' % (t*1e6, n, p, ' '.join(arrs)))
