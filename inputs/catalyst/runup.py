# script-version: 2
# sphdem in-situ extract (ParaView 5.11 legacy Catalyst): the run-up, as the free-surface
# elevation along the centreline. Writes catalyst/runup_<step>.csv per extract step, one row per
# x bin of width dp with fluid in it:
#   x (bin centre), z_surface (highest fluid particle centre in the bin + dp/2), n (particles),
#   t, step
# plus, on every row, runup = the highest z_surface of the step.
# The centreline is the plane y = CENTRELINE_Y (None: the middle of the fluid's y range at that
# step); in 3D only particles within 2h of it count (in 2D every particle is on it).
# Input channel "fluid" (io/insitu.hpp): fluid points; field data dp, h, dim, time, step.
from paraview.simple import *
from paraview import catalyst

CENTRELINE_Y = None

fluid = TrivialProducer(registrationName='fluid')

runup = ProgrammableFilter(registrationName='runup', Input=fluid)
runup.OutputDataSetType = 'vtkTable'
runup.Script = r'''
import numpy as np
from vtkmodules.vtkCommonCore import vtkDoubleArray

data = self.GetInputDataObject(0, 0)
fd = data.GetFieldData()
get = lambda name: fd.GetArray(name).GetTuple1(0)
dp, h, dim = get('dp'), get('h'), int(get('dim'))
pts = np.asarray(inputs[0].Points, dtype=np.float64).reshape(-1, 3)
if dim == 3 and len(pts):
    yc = %r
    if yc is None:
        yc = 0.5 * (pts[:, 1].min() + pts[:, 1].max())
    pts = pts[np.abs(pts[:, 1] - yc) < 2 * h]
rows = {c: [] for c in ('x', 'z_surface', 'n')}
if len(pts):
    x0 = pts[:, 0].min()
    k = np.floor((pts[:, 0] - x0) / dp + 0.5).astype(np.int64)
    top = np.full(k.max() + 1, -np.inf)
    np.maximum.at(top, k, pts[:, 2])
    n = np.bincount(k)
    for b in np.nonzero(n)[0]:
        rows['x'].append(x0 + b * dp)
        rows['z_surface'].append(top[b] + dp / 2)
        rows['n'].append(n[b])
table = self.GetOutput()
peak = max(rows['z_surface']) if rows['z_surface'] else float('nan')
for c in ('x', 'z_surface', 'n', 't', 'step', 'runup'):
    a = vtkDoubleArray()
    a.SetName(c)
    for i in range(len(rows['x'])):
        v = {'t': get('time'), 'step': get('step'), 'runup': peak}.get(c)
        a.InsertNextValue(rows[c][i] if v is None else v)
    table.AddColumn(a)
''' % CENTRELINE_Y

csv = CreateExtractor('CSV', runup, registrationName='runup_csv')
csv.Trigger = 'TimeStep'
csv.Trigger.Frequency = 1  # sphdem calls Catalyst every insitu.every_steps steps
csv.Writer.FileName = 'runup_{timestep:06d}.csv'
csv.Writer.Precision = 12

options = catalyst.Options()
options.GlobalTrigger = 'TimeStep'
options.ExtractsOutputDirectory = '.'  # relative to OUT/catalyst (vtkCPProcessor's folder)
