breccia-geometry 1
dimension 3
particles 3
# tag x y z radius density motion vx vy vz wx wy wz
1 0 0 0 1e-3 2650
2 2e-3 0 0 1e-3 2650 driven 0.1 0 0
3 0 2e-3 0 1e-3 2650 free 0 0 0 0 0 1
bonds 2
1 2
1 3
