# variant.py KIND (rods, coulomb, still, none): rewrite shaders/wgsl for a measurement variant; run from the repository root, `git checkout shaders/wgsl` after building.
import sys, re
kind = sys.argv[1]
root = 'shaders/wgsl/'  # run from the repository's root
def edit(path, f):
    s = open(root + path).read(); t = f(s)
    assert t != s, (path, kind)
    open(root + path, 'w').write(t)
def no_rods_bodies(s):
    a = s.index("    for (var k = 0u; k < p.num_rods; k++) {\n        let c = rod_contact(k, x, p.margin);")
    b = s.index("    return Moved(x, v);\n}", a)
    return s[:a] + s[b:]
def no_coulomb(s):
    s = s.replace("""    if coulomb() {
        return coulomb_contact(x, v, vs, nrm);
    }
    return Moved(x, contact_vel_moving(v, vs, nrm, p.friction));""", """    return Moved(x, contact_vel_moving(v, vs, nrm, p.friction));""")
    s = s.replace("""        if coulomb() {
            return coulomb_contact(xn, vn, vec3<f32>(0.0), vec3<f32>(0.0, 1.0, 0.0));
        }
        vn = contact_vel""", """        vn = contact_vel""")
    return s
def still_spheres(s):
    return s.replace("return Contact(true, r - dist, n, s.center + arm, surface_vel(s.velocity.xyz, s.spin.xyz, arm));",
                     "return Contact(true, r - dist, n, s.center + arm, vec3<f32>(0.0));")
def no_colliders(s):
    a = s.index("    for (var k = 0u; k < p.num_spheres; k++) {\n        let c = sphere_contact(spheres[k], x, p.margin);")
    b = s.index("    return Moved(x, v);\n}", a)
    return s[:a] + s[b:]
steps = {
  'rods': [('shared/colliders.wgsl', no_rods_bodies)],
  'coulomb': [('shared/colliders.wgsl', no_rods_bodies), ('shared/state.wgsl', no_coulomb)],
  'still': [('shared/colliders.wgsl', no_rods_bodies), ('shared/state.wgsl', no_coulomb), ('shared/colliders.wgsl', still_spheres)],
  'none': [('shared/colliders.wgsl', no_colliders)],
}[kind]
for path, f in steps:
    edit(path, f)
