# script-version: 2
# sphdem in-situ extract (ParaView 5.11 legacy Catalyst): the fluid's force on each named solid,
# and the boulders' contact load on it.
# Writes one table per extract step, catalyst/impact_force_<step>.csv, with one row per solid:
#   solid, fx, fy, fz (N; the fluid's force, per unit width in 2D, as impact_force-style CSVs),
#   t, step, grain_fx, grain_fy, grain_fz (N; the grains' DEM contact load on the solid, the
#   mean over the last fluid step as impact_force.csv's barrier_k_grain_fx; 0 without grains).
# Input channel "walls" (io/insitu.hpp): the boundary particles with point arrays force
# (mass * acc) and body (solid index), and field data solid_names, grain_force, time, step.
# The sum runs over the particles in order (cumsum), like the solver's probe_solid_force, so the
# values equal the solver's force diagnostics (diagnostics.forces) at the same step.
# On many ranks each rank holds the walls it owns: the ranks' sums are added (one AllReduce over
# ParaView's global controller) and rank 0 alone writes the rows, so the table is the whole
# force on every solid, as on one rank. grain_force is already whole on every rank.
from paraview.simple import *
from paraview import catalyst

walls = TrivialProducer(registrationName='walls')

forces = ProgrammableFilter(registrationName='impact_force', Input=walls)
forces.OutputDataSetType = 'vtkTable'
forces.Script = r'''
import numpy as np
from vtkmodules.vtkCommonCore import vtkDoubleArray, vtkStringArray
from vtkmodules.vtkParallelCore import vtkCommunicator, vtkMultiProcessController

data = self.GetInputDataObject(0, 0)
fd = data.GetFieldData()
names = fd.GetAbstractArray('solid_names')
if data.GetNumberOfPoints():
    force = np.asarray(inputs[0].PointData['force'], dtype=np.float64).reshape(-1, 3)
    body = np.asarray(inputs[0].PointData['body'])
else:  # a rank that owns no wall particle
    force, body = np.zeros((0, 3)), np.zeros(0, dtype=np.int64)
grain_array = fd.GetArray('grain_force')
if grain_array is None or grain_array.GetNumberOfTuples() != names.GetNumberOfValues():
    raise RuntimeError("impact_force.py: the walls channel has no grain_force field data with "
                       "one tuple per solid (an sphdem older than this script?)")
grains = [grain_array.GetTuple3(s) for s in range(names.GetNumberOfValues())]
nsolid = names.GetNumberOfValues()
mine = vtkDoubleArray()  # this rank's share of each solid's force
mine.SetNumberOfComponents(3)
mine.SetNumberOfTuples(nsolid)
for s in range(nsolid):
    f = force[body == s]
    mine.SetTuple3(s, *(np.cumsum(f, axis=0)[-1] if len(f) else np.zeros(3)))
ctrl = vtkMultiProcessController.GetGlobalController()
rank = ctrl.GetLocalProcessId() if ctrl else 0
if ctrl and ctrl.GetNumberOfProcesses() > 1:
    whole = vtkDoubleArray()
    ctrl.AllReduce(mine, whole, vtkCommunicator.SUM_OP)
else:
    whole = mine
table = self.GetOutput()
cols = {}
solid = vtkStringArray()
solid.SetName('solid')
COLUMNS = ('fx', 'fy', 'fz', 't', 'step', 'grain_fx', 'grain_fy', 'grain_fz')
for c in COLUMNS:
    cols[c] = vtkDoubleArray()
    cols[c].SetName(c)
for s in range(nsolid if rank == 0 else 0):  # the other ranks add no rows
    total = whole.GetTuple3(s)
    solid.InsertNextValue(names.GetValue(s))
    for k, c in enumerate(('fx', 'fy', 'fz')):
        cols[c].InsertNextValue(total[k])
    cols['t'].InsertNextValue(fd.GetArray('time').GetTuple1(0))
    cols['step'].InsertNextValue(fd.GetArray('step').GetTuple1(0))
    for k, c in enumerate(('grain_fx', 'grain_fy', 'grain_fz')):
        cols[c].InsertNextValue(grains[s][k])
table.AddColumn(solid)
for c in COLUMNS:
    table.AddColumn(cols[c])
'''

csv = CreateExtractor('CSV', forces, registrationName='impact_force_csv')
csv.Trigger = 'TimeStep'
csv.Trigger.Frequency = 1  # sphdem calls Catalyst every insitu.every_steps steps
csv.Writer.FileName = 'impact_force_{timestep:06d}.csv'
csv.Writer.Precision = 17
csv.Writer.UseScientificNotation = 1

options = catalyst.Options()
options.GlobalTrigger = 'TimeStep'
options.ExtractsOutputDirectory = '.'  # relative to OUT/catalyst (vtkCPProcessor's folder)
