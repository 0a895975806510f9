# Three bonded spheres of docs/physics.md §8 (R = 0.5 mm) forming a triangle in the x-z plane: sphere 1
# at the bottom, sphere 2 on top of it, sphere 3 beside them. Platens along z load 1 and 2.
breccia-geometry 1
dimension 3
particles 3
# tag x y z radius density [motion [vx vy vz [wx wy wz]]]
1 0                 0 0      0.0005 2650
2 0                 0 0.001  0.0005 2650
3 0.000866025403784 0 0.0005 0.0005 2650
bonds 3
1 2
2 3
1 3
