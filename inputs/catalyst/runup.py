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
# On many ranks each rank holds its own fluid: the bins are laid from the lowest x over all ranks,
# the heights and counts are reduced over ParaView's global controller (max and sum), and rank 0
# alone writes the rows, so the table is the one a single rank writes.
from paraview.simple import *
from paraview import catalyst

CENTRELINE_Y = None

fluid = TrivialProducer(registrationName='fluid')

runup = ProgrammableFilter(registrationName='runup', Input=fluid)
runup.OutputDataSetType = 'vtkTable'
runup.Script = r'''
import numpy as np
from vtkmodules.vtkCommonCore import vtkDoubleArray
from vtkmodules.vtkParallelCore import vtkCommunicator, vtkMultiProcessController

ctrl = vtkMultiProcessController.GetGlobalController()
many = ctrl is not None and ctrl.GetNumberOfProcesses() > 1
rank = ctrl.GetLocalProcessId() if ctrl else 0
BIG = 1e300  # stands for +infinity in the reductions

def reduce(values, op):
    # values (a list of floats), reduced elementwise over the ranks
    send = vtkDoubleArray()
    send.SetNumberOfTuples(len(values))
    for i, v in enumerate(values):
        send.SetValue(i, v)
    if not many:
        return list(values)
    recv = vtkDoubleArray()
    ctrl.AllReduce(send, recv, op)
    return [recv.GetValue(i) for i in range(len(values))]

data = self.GetInputDataObject(0, 0)
fd = data.GetFieldData()
get = lambda name: fd.GetArray(name).GetTuple1(0)
dp, h, dim = get('dp'), get('h'), int(get('dim'))
if data.GetNumberOfPoints():
    pts = np.asarray(inputs[0].Points, dtype=np.float64).reshape(-1, 3)
else:  # a rank that holds no fluid
    pts = np.zeros((0, 3))
if dim == 3:
    yc = %r
    if yc is None:
        lo_y, neg_hi_y = reduce([pts[:, 1].min() if len(pts) else BIG,
                                 -pts[:, 1].max() if len(pts) else BIG], vtkCommunicator.MIN_OP)
        yc = 0.5 * (lo_y - neg_hi_y)
    pts = pts[np.abs(pts[:, 1] - yc) < 2 * h]
rows = {c: [] for c in ('x', 'z_surface', 'n')}
x0 = reduce([pts[:, 0].min() if len(pts) else BIG], vtkCommunicator.MIN_OP)[0]
if x0 < BIG:  # some rank has fluid on the centreline
    k = np.floor((pts[:, 0] - x0) / dp + 0.5).astype(np.int64)
    nbin = int(reduce([float(k.max() + 1) if len(k) else 0.0], vtkCommunicator.MAX_OP)[0])
    top = np.full(nbin, -BIG)
    np.maximum.at(top, k, pts[:, 2])
    n = np.bincount(k, minlength=nbin).astype(np.float64)
    top = np.asarray(reduce(list(top), vtkCommunicator.MAX_OP))
    n = np.asarray(reduce(list(n), vtkCommunicator.SUM_OP))
    for b in np.nonzero(n)[0] if rank == 0 else []:  # the other ranks add no rows
        rows['x'].append(x0 + b * dp)
        rows['z_surface'].append(top[b] + dp / 2)
        rows['n'].append(n[b])
table = self.GetOutput()
# np.max, not max: a ProgrammableFilter's max is numpy_interface.algorithms.max, which reduces
# over the ranks, and only rank 0 has rows.
peak = float(np.max(rows['z_surface'])) if rows['z_surface'] else float('nan')
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
