"""Writes a stack of SHEETS sheets of N x N onto a sphere (scenes/stack.toml's set-up, more
sheets, each turned 15 degrees from the one below, 10 cm apart) with the contact between
triangles, thickness 0.4 of the spacing, and its friction: the device call's big stack.
Usage: python3 stack20.py SHEETS N > stack20.toml"""
import math, sys

sheets, n = int(sys.argv[1]), int(sys.argv[2])
spacing = 1.0 / (n - 1)
print(f'title = "{sheets} sheets of {n} x {n} onto a sphere"')
for k in range(sheets):
    a = math.radians(15 * k)
    across, down = (math.cos(a), 0.0, -math.sin(a)), (math.sin(a), 0.0, math.cos(a))
    # The sheet's top edge centre: half a side back along `down` from the middle.
    top = (-0.5 * down[0], 0.8 + 0.1 * k, -0.5 * down[2])
    print("\n[[cloth]]")
    print(f"n = {n}\nsize = 1.0")
    print("top_center = [%f, %.2f, %f]" % top)
    print("across = [%f, 0.0, %f]" % (across[0], across[2]))
    print("down = [%f, 0.0, %f]" % (down[0], down[2]))
    print('pinning = "none"')
print("\n[floor]\ny = 0.0")
print("\n[[spheres]]\ncenter = [0.0, 0.3, 0.0]\nradius = 0.3")
print(f'\n[params]\nself_collision = "triangles"\nself_thickness = {0.4 * spacing:.5f}')
print("static_friction = 0.6\nkinetic_friction = 0.5")
