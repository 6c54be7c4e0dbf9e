# script-version: 2
# sphdem in-situ extract (ParaView 5.11 legacy Catalyst): a decimated particle cloud. Keeps every
# ON_RATIO-th fluid particle (with vel, rho, press, id) and writes
# catalyst/particles_<step>.vtp per extract step (open the series in ParaView).
# Input channel "fluid" (io/insitu.hpp).
from paraview.simple import *
from paraview import catalyst

ON_RATIO = 4

fluid = TrivialProducer(registrationName='fluid')

decimated = MaskPoints(registrationName='decimated', Input=fluid)
decimated.OnRatio = ON_RATIO
decimated.MaximumNumberofPoints = 2000000000
decimated.GenerateVertices = 1
decimated.SingleVertexPerCell = 1

vtp = CreateExtractor('VTP', decimated, registrationName='particles_vtp')
vtp.Trigger = 'TimeStep'
vtp.Trigger.Frequency = 1  # sphdem calls Catalyst every insitu.every_steps steps
vtp.Writer.FileName = 'particles_{timestep:06d}.vtp'

options = catalyst.Options()
options.GlobalTrigger = 'TimeStep'
options.ExtractsOutputDirectory = '.'  # relative to OUT/catalyst (vtkCPProcessor's folder)
