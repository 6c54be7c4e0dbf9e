# script-version: 2
# sphdem in-situ extract (ParaView 5.11 legacy Catalyst): the fluid's force on each named solid.
# Writes one table per extract step, catalyst/impact_force_<step>.csv, with one row per solid:
#   solid, fx, fy, fz (N; the force per unit width in 2D, as impact_force-style CSVs), t, step.
# Input channel "walls" (io/insitu.hpp): the boundary particles with point arrays force
# (mass * acc) and body (solid index), and field data solid_names, time, step.
# The sum runs over the particles in order (cumsum), like the solver's probe_solid_force, so the
# values equal the solver's force diagnostics (diagnostics.forces) at the same step.
from paraview.simple import *
from paraview import catalyst

walls = TrivialProducer(registrationName='walls')

forces = ProgrammableFilter(registrationName='impact_force', Input=walls)
forces.OutputDataSetType = 'vtkTable'
forces.Script = r'''
import numpy as np
from vtkmodules.vtkCommonCore import vtkDoubleArray, vtkStringArray

data = self.GetInputDataObject(0, 0)
fd = data.GetFieldData()
names = fd.GetAbstractArray('solid_names')
force = np.asarray(inputs[0].PointData['force'], dtype=np.float64).reshape(-1, 3)
body = np.asarray(inputs[0].PointData['body'])
table = self.GetOutput()
cols = {}
solid = vtkStringArray()
solid.SetName('solid')
for c in ('fx', 'fy', 'fz', 't', 'step'):
    cols[c] = vtkDoubleArray()
    cols[c].SetName(c)
for s in range(names.GetNumberOfValues()):
    f = force[body == s]
    total = np.cumsum(f, axis=0)[-1] if len(f) else np.zeros(3)
    solid.InsertNextValue(names.GetValue(s))
    for k, c in enumerate(('fx', 'fy', 'fz')):
        cols[c].InsertNextValue(total[k])
    cols['t'].InsertNextValue(fd.GetArray('time').GetTuple1(0))
    cols['step'].InsertNextValue(fd.GetArray('step').GetTuple1(0))
table.AddColumn(solid)
for c in ('fx', 'fy', 'fz', 't', 'step'):
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
