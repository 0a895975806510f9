LSMGeometry 1.2
BoundingBox 0 0 0 5 5 5
PeriodicBoundaries 0 0 0
Dimension 3D
BeginParticles
Simple
3
0 0 0 0.5 0 1
1.1 0 0 0.5 1 1
0 1.1 0 0.5 2 1
EndParticles
BeginConnect
2
0 1 0
0 2 0
EndConnect
