"""Taichi's cloth example (taichi/examples/ggui_examples/mass_spring_3d_ggui.py, Taichi
1.7.4: the mass-spring cloth falling on a ball, 12 springs per particle, one kernel per
substep) without its window, timed: ns per particle-substep, the unit `clothlab sim`
prints. Usage: python3 taichi_cloth.py ARCH N SUBSTEPS (ARCH: vulkan | cpu; the CPU
backend runs on `TI_THREADS` threads, default 2)."""
import os
import sys
import time

import taichi as ti

arch_name, n, steps = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])
arch = {"vulkan": ti.vulkan, "cpu": ti.cpu}[arch_name]
ti.init(arch=arch, cpu_max_num_threads=int(os.environ.get("TI_THREADS", "2")), log_level=ti.WARN)

quad_size = 1.0 / n
dt = 4e-2 / n
gravity = ti.Vector([0, -9.8, 0])
spring_Y = 3e4
dashpot_damping = 1e4
drag_damping = 1
ball_radius = 0.3
ball_center = ti.Vector.field(3, dtype=float, shape=(1,))
ball_center[0] = [0, 0, 0]
x = ti.Vector.field(3, dtype=float, shape=(n, n))
v = ti.Vector.field(3, dtype=float, shape=(n, n))
spring_offsets = [ti.Vector([i, j]) for i in range(-2, 3) for j in range(-2, 3) if (i, j) != (0, 0) and abs(i) + abs(j) <= 2]


@ti.kernel
def initialize_mass_points():
    for i, j in x:
        x[i, j] = [i * quad_size - 0.5, 0.6, j * quad_size - 0.5]
        v[i, j] = [0, 0, 0]


@ti.kernel
def substep():
    for i in ti.grouped(x):
        v[i] += gravity * dt
    for i in ti.grouped(x):
        force = ti.Vector([0.0, 0.0, 0.0])
        for spring_offset in ti.static(spring_offsets):
            j = i + spring_offset
            if 0 <= j[0] < n and 0 <= j[1] < n:
                x_ij = x[i] - x[j]
                v_ij = v[i] - v[j]
                d = x_ij.normalized()
                current_dist = x_ij.norm()
                original_dist = quad_size * float(i - j).norm()
                force += -spring_Y * d * (current_dist / original_dist - 1)
                force += -v_ij.dot(d) * d * dashpot_damping * quad_size
        v[i] += force * dt
    for i in ti.grouped(x):
        v[i] *= ti.exp(-drag_damping * dt)
        offset_to_center = x[i] - ball_center[0]
        if offset_to_center.norm() <= ball_radius:
            normal = offset_to_center.normalized()
            v[i] -= ti.min(v[i].dot(normal), 0) * normal
        x[i] += dt * v[i]


initialize_mass_points()
for _ in range(16):  # compile and warm up
    substep()
ti.sync()
samples = []
for _ in range(5):
    t = time.perf_counter()
    for _ in range(steps):
        substep()
    ti.sync()
    samples.append((time.perf_counter() - t) / steps / (n * n) * 1e9)
samples.sort()
print(f"taichi {arch_name} n={n} ns/particle-substep median {samples[2]:.2f} min {samples[0]:.2f} max {samples[-1]:.2f}")
