# A Catalyst script in the old (version 1) format: sphdem refuses it (ParaView 5.11 legacy
# Catalyst runs "# script-version: 2" scripts only).
from paraview.simple import *
