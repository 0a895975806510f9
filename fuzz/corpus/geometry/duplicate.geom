breccia-geometry 1
particles 2
1 0 0 0 1e-3 2650
1 0 0 0 1e-3 2650
