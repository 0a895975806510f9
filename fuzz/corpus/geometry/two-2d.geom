breccia-geometry 1
dimension 2
thickness 0.001
particles 2
1 0 0 0 1e-3 2650
2 2e-3 0 0 1e-3 2650
bonds 1
1 2
