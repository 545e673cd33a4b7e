//! The serial and rayon solvers: the step of DESIGN.md, one kernel after another.

use std::time::Instant;

use super::fused::{self, Band, Soa, TetherLanes};
use super::simd::Simd;
use super::{
    AUX, CgScalars, Exec, FaceLanes, HashBuffers, Lanes, RK2, RK4, XPBD_ORDER, build_hash, cg_alpha, cg_begin, cg_beta,
    cg_direction, cg_matvec, cg_step, collide, euler, fold, forces, hash_buffers, implicit_finish, integrate,
    integrate_collide, partial_sums, rk_begin, rk_stage, self_collide, springs_rows, strain_count, strain_limit,
    strain_limit_rows, strain_vel, tri_normals, tri_normals_lanes, vertex_normals, vertex_normals_rows, xpbd_mesh_pass,
    xpbd_pass, xpbd_pass_rows,
};
use clothlab_core::cloth::build;
use clothlab_core::grid::{ClothState, ClothTopology, Grab, SLOTS, SpringSlot, V4};
use clothlab_core::params::{Integrator, SimParams};
use clothlab_core::scene::Scene;
use clothlab_core::solver::{Solver, SolverError};
use clothlab_core::step_params::StepParams;
use clothlab_core::substep::{Integration, Stage};
use clothlab_core::timing::{
    FORCES_SPRINGS, FRAME, FUSED_STEP, INTEGRATE_COLLIDE, KernelTimings, SELF_COLLIDE, SELF_HASH, STRAIN_LIMIT,
    SUBSTEP, TRI_BOUNDS, TRI_CONTACT, TRI_NORMALS, TimingRecorder, VERTEX_NORMALS,
};

/// The CPU solver; [`Exec::Serial`] is the thesis's CPU variant, [`Exec::Parallel`] its
/// OpenMP one. Both run the same gather kernels, so they agree bit for bit.
pub struct CpuSolver {
    exec: Exec,
    scene: Scene,
    /// The colliders at the current substep (the scene's, moved: `Scene::colliders_at`).
    colliders: super::collide::ColliderSet,
    /// Simulated time, s.
    time: f64,
    params: SimParams,
    grab: Option<Grab>,
    state: ClothState,
    topo: ClothTopology,
    /// Strain-limit ping-pong target.
    scratch: Vec<V4>,
    /// Each particle's count of over-stretched springs before a strain pass
    /// (`strain_count`; the kernels keep it in aux0).
    strain_counts: Vec<f32>,
    /// Face normals, one per triangle.
    face: Vec<V4>,
    /// Structure-of-arrays copy of the state for the SIMD paths.
    lanes: Lanes,
    /// Face normals for the SIMD paths.
    face_lanes: FaceLanes,
    /// The interior's uniform spring slots, if the table has them (the fast path).
    uniform: Option<[SpringSlot; SLOTS]>,
    /// The slots of the regular grid, if the whole table is one (the fused sweep's).
    grid: Option<[SpringSlot; SLOTS]>,
    /// The integrators' scratch buffers (see `integrators.rs`), allocated when one needs them.
    aux: Vec<Vec<V4>>,
    /// The conjugate-gradient scalars.
    cg: CgScalars,
    timer: TimingRecorder,
    /// Record per-kernel timings (costs two `Instant::now` per kernel).
    pub time_kernels: bool,
    /// Run Verlet substeps as one sweep (`fused.rs`) where the grid allows; off, kernel by
    /// kernel with a timing per kernel. The two compute the same bits.
    pub fused: bool,
    /// The instruction set of the fused sweep.
    simd: Simd,
    /// The fused sweep's per-band rings.
    bands: Vec<Band>,
    /// The state as the fused sweep keeps it, and where a sweep writes the next one.
    soa: [Soa; 2],
    /// `soa[0]` holds the current state (else `state` does, and `soa` is loaded from it).
    soa_valid: bool,
    /// `state` is behind `soa[0]` (fused substeps ran since it was last written).
    aos_stale: bool,
    /// The particles the tethers hold to (the fused sweep needs them pinned).
    pins: Vec<usize>,
    /// The tethers as component arrays, for the fused sweep.
    tether_lanes: TetherLanes,
    /// A mesh's springs' λ (XPBD; empty for a grid).
    mesh_lambda: Vec<f32>,
    /// The contact between triangles' buffers (`self_collision = "triangles"`), made when
    /// a substep first needs them.
    contact: Option<crate::tri_pipeline::Contact>,
}

impl CpuSolver {
    /// Builds the cloth of `scene` and computes its initial normals.
    pub fn new(exec: Exec, scene: Scene, params: SimParams) -> Result<Self, SolverError> {
        let (state, topo) = build(&scene, &params)?;
        let np = state.pos.len();
        let colliders = super::collide::ColliderSet::new(&scene);
        let mut s = Self {
            exec,
            scene,
            colliders,
            time: 0.0,
            params,
            grab: None,
            scratch: vec![[0.0; 4]; np],
            strain_counts: vec![0.0; np],
            face: vec![[0.0; 4]; topo.triangles.len()],
            uniform: topo.uniform_interior_slots(),
            grid: topo.grid_slots(),
            lanes: Lanes::default(),
            face_lanes: FaceLanes::default(),
            aux: Vec::new(),
            cg: [0.0; 4],
            state,
            topo,
            timer: TimingRecorder::default(),
            time_kernels: true,
            fused: super::simd::fused_from_env().map_err(SolverError::Unsupported)?,
            simd: Simd::from_env().map_err(SolverError::Unsupported)?,
            bands: Vec::new(),
            soa: Default::default(),
            soa_valid: false,
            aos_stale: false,
            pins: Vec::new(),
            tether_lanes: TetherLanes::default(),
            mesh_lambda: Vec::new(),
            contact: None,
        };
        if s.topo.mesh.is_some() {
            s.mesh_lambda = vec![0.0; s.topo.springs.len()];
        }
        s.tether_lanes = TetherLanes::new(&s.topo.tethers);
        s.pins = s.topo.tethers.iter().flatten().filter(|t| t.pin >= 0).map(|t| t.pin as usize).collect();
        s.pins.sort_unstable();
        s.pins.dedup();
        s.update_normals();
        Ok(s)
    }

    /// The connectivity and spring constants.
    pub fn topology(&self) -> &ClothTopology {
        &self.topo
    }

    /// The instruction set (and so the vector width) of the fused sweep.
    pub fn simd(&self) -> Simd {
        self.simd
    }

    /// Runs the fused sweep on `simd` (refused when this CPU lacks it).
    pub fn set_simd(&mut self, simd: Simd) -> Result<(), SolverError> {
        if !simd.available() {
            return Err(SolverError::Unsupported(format!(
                "this CPU has no {}; it has {}",
                simd.name(),
                Simd::detect()
            )));
        }
        self.simd = simd;
        Ok(())
    }

    /// Whether the next substep runs fused: Verlet (or symplectic Euler) on a regular grid
    /// without self-collision, every tether's pin pinned, and `fused` on.
    pub fn runs_fused(&self) -> bool {
        self.fused
            && self.grid.is_some()
            && matches!(self.params.integrator, Integrator::Verlet | Integrator::SymplecticEuler)
            && !self.params.self_collision.on()
            && self.topo.n >= 8
            && self.pins.iter().all(|&k| self.state.pos[k][3] == 0.0)
    }

    /// How the next Verlet substeps run, in words: the fused sweep and its instruction
    /// set, or kernel by kernel and why.
    pub fn path(&self) -> String {
        if self.runs_fused() {
            return format!("fused sweep on {}", self.simd);
        }
        let why = if !self.fused {
            "the fused sweep switched off: CLOTHLAB_CPU_FUSED=off".to_owned()
        } else if !matches!(self.params.integrator, Integrator::Verlet | Integrator::SymplecticEuler) {
            format!("the fused sweep runs Verlet only, not {:?}", self.params.integrator)
        } else if self.params.self_collision.on() {
            "the fused sweep has no self-collision".to_owned()
        } else if self.topo.mesh.is_some() {
            "the fused sweep is the grid's; a mesh runs its kernels over the tables".to_owned()
        } else if self.grid.is_none() || self.topo.n < 8 {
            "the grid is too small or not uniform for the fused sweep".to_owned()
        } else {
            "a tether's pin is not pinned".to_owned()
        };
        format!("kernel by kernel ({why})")
    }

    /// The fused substep (see `fused.rs`), on `soa`; `state` is left behind until
    /// [`Self::sync`].
    fn substep_fused(&mut self) {
        let p = self.step_params();
        let t0 = Instant::now();
        if !self.soa_valid {
            self.soa[0].load(self.exec, &self.state);
            self.soa_valid = true;
        }
        self.soa[1].resize(self.state.pos.len());
        let Self { topo, timer, colliders, params, grid, bands, soa, exec, simd, tether_lanes, .. } = self;
        let Some(uni) = grid.as_ref() else { return };
        let [old, next] = soa;
        let step = fused::Step {
            p: &p,
            iters: params.strain_iterations as usize,
            uni,
            tethers: &topo.tethers,
            tether_lanes,
            face_slots: &topo.face_slots,
            colliders: colliders.view(),
            old,
        };
        fused::substep(*exec, *simd, &step, bands, next);
        std::mem::swap(old, next);
        self.aos_stale = true;
        if self.time_kernels {
            let ns = t0.elapsed().as_nanos() as f64;
            timer.record(FUSED_STEP, ns);
            timer.record(SUBSTEP, ns);
        }
    }

    /// Brings `state` up to the fused substeps run since it was last written.
    fn sync(&mut self) {
        if self.aos_stale {
            self.soa[0].store(self.exec, &mut self.state);
            self.aos_stale = false;
        }
    }

    /// One substep, fused or kernel by kernel, leaving `state` behind after a fused one.
    fn substep_inner(&mut self) {
        if self.scene.moves() {
            self.colliders.move_to(&self.scene, self.time);
        }
        let t0 = self.time;
        self.time += self.params.dt() as f64;
        // Moving pins go to their pose at the substep's start or end, as the integrator
        // takes them (clothlab_core::pins::at_substep_end).
        // A group moved by its motion or by a script has slots (`pins::moving`).
        let poses = (!self.topo.pins.slots.is_empty()).then(|| {
            clothlab_core::pins::frame_poses(
                &self.scene.pins,
                &self.topo.pins.pivots,
                self.params.integrator,
                t0,
                self.params.dt() as f64,
                1,
            )
        });
        if self.runs_fused() {
            if let Some(poses) = &poses {
                if !self.soa_valid {
                    self.soa[0].load(self.exec, &self.state);
                    self.soa_valid = true;
                }
                self.soa[0].drive(&self.topo.pins.slots, poses);
            }
            self.substep_fused();
        } else {
            self.sync();
            if let Some(poses) = &poses {
                clothlab_core::pins::drive(&self.topo.pins.slots, poses, 0, &mut self.state.pos, &mut self.state.vel);
            }
            self.substep_kernels();
            self.soa_valid = false;
        }
    }

    /// The current state, borrowed (no copy).
    pub fn state_ref(&self) -> &ClothState {
        &self.state
    }

    /// The per-step constants in use.
    pub fn step_params(&self) -> StepParams {
        StepParams::new(&self.params, &self.scene, self.grab)
    }

    fn update_normals(&mut self) {
        let p = self.step_params();
        tri_normals(self.exec, &self.topo.triangles, &self.state.pos, &mut self.face);
        vertex_normals(self.exec, &p, &self.topo.face_slots, &self.face, &mut self.state.normal, &mut self.state.force);
    }

    /// One substep: the kernels of DESIGN.md's step, in order. Kernels that touch only
    /// their own particle run fused with their neighbour in the step (`forces` into
    /// `springs`, `integrate` with `collide`), and on a regular grid the gathers run on
    /// SIMD lanes; every path computes the twins' bits (tests/physics.rs checks it), so
    /// GPU kernels compared with the twins are compared with this solver.
    pub fn substep(&mut self) {
        self.substep_inner();
        self.sync();
    }

    /// One substep kernel by kernel: the stages of [`Integration::stages`] (the order the
    /// engine's recipes follow too; tests/tests/suite/integrators.rs checks the bits),
    /// each as its twins — the forces fused into the spring gather, the update with the
    /// colliders where one follows the other, the gathers on SIMD rows on a regular grid.
    /// Each label's time is the substep's sum over the stages it names.
    fn substep_kernels(&mut self) {
        let p = self.step_params();
        let e = self.exec;
        let on = self.time_kernels;
        let t0 = Instant::now();
        let stages = Integration::of(&self.params).stages(self.params.strain_iterations);
        let Self {
            state,
            topo,
            scratch,
            strain_counts,
            face,
            timer,
            colliders,
            params,
            uniform,
            lanes,
            face_lanes,
            aux,
            cg,
            grid,
            mesh_lambda,
            contact,
            exec,
            ..
        } = self;
        // VBD takes the contact between triangles inside its solves.
        let vbd_contact = params.self_collision.triangles() && params.integrator == Integrator::Vbd;
        if params.self_collision.triangles() && contact.is_none() {
            *contact = Some(crate::tri_pipeline::Contact::new(&topo.triangles, *exec == Exec::Parallel));
        }
        let n = topo.n as usize;
        let fast = uniform.is_some();
        let mesh = topo.mesh.is_some();
        // The gather's rows: the grid's, or for a mesh chunks of particles (no row fast path).
        let rows = if mesh { 1024 } else { n };
        let ClothState { pos, vel, force, normal, .. } = state;
        // The force of the current (pos, vel): forces fused into the spring gather.
        let eval = |lanes: &mut Lanes, pos: &[V4], vel: &[V4], force: &mut [V4]| {
            if fast {
                lanes.fill(e, n, pos, Some(vel));
            }
            springs_rows(e, rows, &topo.slots, uniform.as_ref(), Some(&p), lanes, pos, vel, force)
        };
        let c = colliders.view();
        let needs_aux = params.self_collision.particles()
            || !matches!(params.integrator, Integrator::Verlet | Integrator::SymplecticEuler);
        if needs_aux && aux.len() != AUX {
            *aux = vec![vec![[0.0; 4]; pos.len()]; AUX];
        }
        // Sums as the kernels make them: per workgroup, then folded.
        let total = |terms: Vec<f32>| fold(&partial_sums(&terms));
        // The time spent per label in this substep.
        let mut spent: Vec<(&'static str, f64)> = Vec::new();
        let mut add = |label: &'static str, t: Option<Instant>| {
            if let Some(t) = t {
                let ns = t.elapsed().as_nanos() as f64;
                match spent.iter_mut().find(|(l, _)| *l == label) {
                    Some((_, s)) => *s += ns,
                    None => spent.push((label, ns)),
                }
            }
        };
        let now = || on.then(Instant::now);
        let mut sweeps = 0;
        let mut lambda_cleared = false;
        let mut rest = &stages[..];
        while let Some((&stage, tail)) = rest.split_first() {
            rest = tail;
            let t = now();
            let label = match stage {
                Stage::Eval => {
                    eval(lanes, pos, vel, force);
                    FORCES_SPRINGS
                }
                // The update and the colliders in one pass where one follows the other.
                Stage::Integrate if rest.first() == Some(&Stage::Collide) => {
                    rest = &rest[1..];
                    integrate_collide(e, &p, c, force, pos, vel);
                    INTEGRATE_COLLIDE
                }
                Stage::Integrate => {
                    integrate(e, &p, force, pos, vel);
                    INTEGRATE_COLLIDE
                }
                Stage::Forces => {
                    forces(e, &p, pos, vel, force);
                    INTEGRATE_COLLIDE
                }
                Stage::Euler => {
                    euler(e, &p, force, pos, vel);
                    INTEGRATE_COLLIDE
                }
                Stage::RkBegin => {
                    rk_begin(e, &p, force, pos, vel, aux);
                    INTEGRATE_COLLIDE
                }
                Stage::Rk { order, stage } => {
                    let stages: &[super::RkStage] = if order == 2 { &RK2 } else { &RK4 };
                    rk_stage(e, &p, &stages[stage as usize], force, pos, vel, aux);
                    INTEGRATE_COLLIDE
                }
                Stage::CgBegin => {
                    let rz = total(cg_begin(e, &p, &topo.slots, force, pos, vel, aux));
                    cg_beta(cg, rz);
                    INTEGRATE_COLLIDE
                }
                Stage::CgIteration => {
                    let pq = total(cg_matvec(e, &p, &topo.slots, pos, aux));
                    cg_alpha(cg, pq);
                    let rz = total(cg_step(e, cg, aux));
                    cg_beta(cg, rz);
                    cg_direction(e, cg, aux);
                    INTEGRATE_COLLIDE
                }
                Stage::ImplicitFinish => {
                    implicit_finish(e, &p, pos, vel, aux);
                    INTEGRATE_COLLIDE
                }
                Stage::XpbdIteration => {
                    // λ per spring, from zero every substep (the recipe's clears).
                    if !lambda_cleared {
                        lambda_cleared = true;
                        aux[..2].iter_mut().flatten().for_each(|v| *v = [0.0; 4]);
                        mesh_lambda.iter_mut().for_each(|l| *l = 0.0);
                    }
                    if let Some(m) = &topo.mesh {
                        for pass in m.xpbd_passes.windows(2) {
                            let range = pass[0] as usize..pass[1] as usize;
                            xpbd_mesh_pass(e, &p, &topo.springs, range, pos, vel, mesh_lambda);
                        }
                    } else {
                        for pass in XPBD_ORDER {
                            if grid.is_some() {
                                xpbd_pass_rows(e, &p, &topo.slots, pass, pos, vel, aux);
                            } else {
                                xpbd_pass(&p, &topo.slots, pass, pos, vel, aux);
                            }
                        }
                    }
                    INTEGRATE_COLLIDE
                }
                Stage::VbdBegin => {
                    super::vbd::vbd_begin(e, &p, force, pos, vel, aux);
                    if vbd_contact {
                        // The contact's terms are found at the iterate (the positions are
                        // the substep's start until the finish otherwise).
                        super::vbd::vbd_positions(e, pos, aux);
                    }
                    INTEGRATE_COLLIDE
                }
                Stage::VbdSweep => {
                    sweeps += 1;
                    for k in 0..topo.colours.len() {
                        let colour = topo.colours.colour(k);
                        let tri = contact.as_mut().filter(|_| vbd_contact).map(|ct| {
                            ct.vbd_terms(&p, pos, &topo.triangles, &topo.colours.of, k as u32);
                            super::vbd::TriVbd { sums: ct.vbd_sums(), pos: &mut pos[..] }
                        });
                        super::vbd::vbd_colour(e, &p, &topo.slots, c, colour, aux, tri);
                    }
                    clothlab_core::timing::VBD
                }
                Stage::VbdAccelerate => {
                    let omega = super::vbd::chebyshev_omega(sweeps, params.vbd_rho);
                    super::vbd::vbd_accelerate(e, &p, omega, aux);
                    if vbd_contact {
                        super::vbd::vbd_positions(e, pos, aux);
                    }
                    clothlab_core::timing::VBD
                }
                Stage::VbdFinish => {
                    super::vbd::vbd_finish(e, &p, pos, vel, aux);
                    INTEGRATE_COLLIDE
                }
                Stage::Collide => {
                    collide(e, &p, c, pos, vel);
                    INTEGRATE_COLLIDE
                }
                Stage::StrainPass(_) => {
                    if fast {
                        lanes.fill(e, n, pos, None);
                    }
                    strain_count(e, &p, &topo.slots, pos, strain_counts);
                    if mesh {
                        strain_limit(e, &p, &topo.slots, &topo.tethers, pos, strain_counts, scratch);
                    } else {
                        strain_limit_rows(
                            e,
                            &p,
                            &topo.slots,
                            uniform.as_ref(),
                            &topo.tethers,
                            lanes,
                            pos,
                            strain_counts,
                            scratch,
                        );
                    }
                    strain_vel(e, &p, pos, scratch, vel);
                    std::mem::swap(pos, scratch);
                    STRAIN_LIMIT
                }
                // The hash in aux2, aux3 and aux4, the velocities' copy for friction in aux0
                // (all dead after the integrator's kernels), the response into the other
                // position buffer (self_collide.rs).
                Stage::SelfCollision => {
                    let mut h = hash_buffers(aux);
                    build_hash(&p, pos, vel, &mut h);
                    add(SELF_HASH, t);
                    let t = now();
                    let HashBuffers { cells, slots, vel_copy, .. } = h;
                    self_collide(e, &p, pos, vel, cells, slots, vel_copy, Some(&topo.slots), scratch);
                    std::mem::swap(pos, scratch);
                    add(SELF_COLLIDE, t);
                    continue;
                }
                Stage::TriangleBounds => {
                    if let Some(c) = contact {
                        c.begin(&p, pos, vel, &topo.triangles, params.search_margin);
                    }
                    TRI_BOUNDS
                }
                Stage::TriangleSeparate => {
                    if let Some(c) = contact {
                        c.separate(&p, pos, vel, &topo.triangles);
                    }
                    TRI_CONTACT
                }
                Stage::TriangleClamp => {
                    if let Some(c) = contact {
                        c.clamp(&p, pos, vel, &topo.triangles);
                    }
                    TRI_CONTACT
                }
                Stage::Normals => {
                    if fast {
                        lanes.fill(e, n, pos, None);
                        tri_normals_lanes(e, n, lanes, face_lanes);
                        add(TRI_NORMALS, t);
                        let t = now();
                        vertex_normals_rows(e, &p, &topo.face_slots, face_lanes, normal, force);
                        add(VERTEX_NORMALS, t);
                    } else {
                        tri_normals(e, &topo.triangles, pos, face);
                        add(TRI_NORMALS, t);
                        let t = now();
                        vertex_normals(e, &p, &topo.face_slots, face, normal, force);
                        add(VERTEX_NORMALS, t);
                    }
                    continue;
                }
            };
            add(label, t);
        }
        if on {
            for (label, ns) in spent {
                timer.record(label, ns);
            }
            timer.record(SUBSTEP, t0.elapsed().as_nanos() as f64);
        }
    }
}

impl Solver for CpuSolver {
    fn name(&self) -> &str {
        match self.exec {
            Exec::Serial => "cpu",
            Exec::Parallel => "cpu-par",
        }
    }

    fn scene(&self) -> &Scene {
        &self.scene
    }

    fn params(&self) -> &SimParams {
        &self.params
    }

    fn set_params(&mut self, params: SimParams) -> Result<(), SolverError> {
        self.topo.validate_params(&params)?;
        self.scene.check_motion_speed(params.dt())?;
        self.sync();
        self.soa_valid = false;
        self.params = params;
        self.topo.set_spring_constants(&self.params);
        self.uniform = self.topo.uniform_interior_slots();
        self.grid = self.topo.grid_slots();
        Ok(())
    }

    fn set_grab(&mut self, grab: Option<Grab>) {
        self.grab = Grab::checked(grab, self.state.pos.len());
    }

    fn step_frame(&mut self) -> Result<(), SolverError> {
        let t0 = Instant::now();
        for _ in 0..self.params.substeps {
            self.substep_inner();
        }
        self.sync();
        if self.time_kernels {
            self.timer.record(FRAME, t0.elapsed().as_nanos() as f64);
        }
        Ok(())
    }

    fn state(&mut self) -> Result<ClothState, SolverError> {
        Ok(self.state.clone())
    }

    fn contact_stats(&self) -> Option<clothlab_core::solver::ContactStats> {
        self.contact.as_ref().map(|c| c.stats())
    }

    fn field(&mut self, field: clothlab_core::solver::StateField) -> Result<Vec<clothlab_core::grid::V4>, SolverError> {
        use clothlab_core::solver::StateField;
        Ok(match field {
            StateField::Pos => self.state.pos.clone(),
            StateField::Vel => self.state.vel.clone(),
            StateField::Force => self.state.force.clone(),
            StateField::Normal => self.state.normal.clone(),
        })
    }

    fn set_state(&mut self, state: &ClothState) -> Result<(), SolverError> {
        state.check(&self.topo)?;
        self.state = state.clone();
        (self.soa_valid, self.aos_stale) = (false, false);
        Ok(())
    }

    fn time(&self) -> f64 {
        self.time
    }

    fn set_time(&mut self, t: f64) -> Result<(), SolverError> {
        self.time = clothlab_core::solver::checked_time(t)?;
        Ok(())
    }

    fn timings(&self) -> KernelTimings {
        self.timer.table()
    }

    fn set_pin_motion(&mut self, group: usize, motion: clothlab_core::motion::Motion) -> Result<(), SolverError> {
        Ok(clothlab_core::pins::set_scripted(&mut self.scene.pins, group, motion)?)
    }

    fn reset_timings(&mut self) {
        self.timer.clear();
    }
}
