// The total force on every particle and, for the implicit schemes, the pieces of its Jacobian (port of
// bf41571:fmu_src/wetcloth/kernels/assembly.py).  Each force family is one call, skipped when the scene does not need
// it: no spring kernel without springs, no water kernels while no particle touches the water, no drag in
// air without air (air_density 0).  A new force family is one more call here, adding to force and, for
// the implicit schemes, to the per-particle blocks or to the per-spring blocks that the system matrix uses.
#include "wetcloth/assembly.hpp"

#include "wetcloth/listed_springs.hpp"
#include "wetcloth/mesh_records.hpp"
#include "wetcloth/springs.hpp"
#include "wetcloth/water.hpp"

namespace wc {
namespace {

//: force (3, n) = gravity on the dry mass plus the absorbed water (kg).
inline void gravity_loop(Index n, const double* __restrict dry_mass, const double* __restrict water,
                         double* __restrict fx, double* __restrict fy, double* __restrict fz) {
    for (Index i = 0; i < n; ++i) {
        fx[i] = 0.0;
        fy[i] = 0.0;
        fz[i] = -(dry_mass[i] + water[i]) * GRAVITY;
    }
}

void start_with_gravity(const Cloth& cloth, const double* water, double* force) {
    const Index n = cloth.n;
    gravity_loop(n, cloth.dry_mass, water, force, force + n, force + 2 * n);
}

//: The Stokes drag's velocity Jacobian times h on the blocks' diagonal: h 6 pi a eta s (N s/m * s).
inline void stokes_blocks_loop(Index n, double h, const double* __restrict coefficient, const double* __restrict s,
                               double* __restrict xx, double* __restrict yy, double* __restrict zz) {
    for (Index i = 0; i < n; ++i) {
        const double c = h * coefficient[i] * s[i];
        xx[i] += c;
        yy[i] += c;
        zz[i] += c;
    }
}

//: saturation = water / capacity, only while wetness-dependent stiffness is on.
void update_saturation(const Cloth& cloth, const Physics& phys, const double* __restrict water,
                       double* __restrict saturation) {
    if (phys.wet_factor != 0.0) {
        const double* __restrict capacity = cloth.capacity;
        for (Index i = 0; i < cloth.n; ++i) saturation[i] = water[i] / capacity[i];
    }
}

void fill_zero(double* a, Index count) {
    for (Index i = 0; i < count; ++i) a[i] = 0.0;
}

//: The face drag of `fluid` on a grid's cells into work.force and, with blocks_wanted, h times its
//: velocity Jacobian into work.blocks.
void add_face_drag(const Cloth& cloth, const Physics& phys, Work& work, const double* pos, const double* vel,
                   const Fluid& fluid, double h, bool blocks_wanted) {
    if (blocks_wanted) {
        face_drag_and_blocks(cloth.grid_x, cloth.grid_y, pos, vel, work.submerged, fluid, h, work.force, work.blocks,
                             work.cells, phys.skip_idle);
    } else {
        face_drag(cloth.grid_x, cloth.grid_y, pos, vel, work.submerged, fluid, work.force, work.cells, phys.skip_idle);
    }
}

//: Smooth buoyancy's position Jacobian times h^2 into blocks: dF_z/dz = -rho g V / thickness inside the
//: surface slab (0 < s < 1).
void add_buoyancy_blocks(const Cloth& cloth, const Physics& phys, const double* s, double h, double* blocks) {
    const Index n = cloth.n;
    const double scale = h * h * phys.water_density * GRAVITY / phys.thickness;
    for (Index i = 0; i < n; ++i) {
        if (0.0 < s[i] && s[i] < 1.0) blocks[2 * n + i] += scale * cloth.volume[i];
    }
}

//: Buoyancy and drag (Stokes or face) into work.force; with blocks_wanted their velocity Jacobian
//: (times h) into work.blocks and, for smooth buoyancy, its position Jacobian (times h^2) into
//: work.blocks.
void water_forces(const Cloth& cloth, const Physics& phys, Work& work, const double* pos, const double* vel, double h,
                  bool blocks_wanted) {
    const Index n = cloth.n;
    const double* s = work.submerged;
    double* force = work.force;
    double* blocks = work.blocks;
    buoyancy(n, s, cloth.volume, phys.water_density, GRAVITY, force);
    if (phys.stokes) {
        stokes_drag(n, s, cloth.stokes_coefficient, phys.current_x, phys.current_y, vel, force);
        if (blocks_wanted) stokes_blocks_loop(n, h, cloth.stokes_coefficient, s, blocks, blocks + n, blocks + 2 * n);
    } else {
        add_face_drag(cloth, phys, work, pos, vel, water_fluid(phys), h, blocks_wanted);
    }
    if (blocks_wanted && phys.smooth) add_buoyancy_blocks(cloth, phys, s, h, blocks);
}

//: forces (blocks_wanted false) or forces_and_blocks of a mesh: gravity, its listed springs and face drag
//: summed in its records (mesh_records.hpp) and stored in the rows, then the per-particle water forces.
void mesh_forces(const Cloth& cloth, const Physics& phys, Work& work, const double* pos, const double* vel,
                 const double* water, double h, double slack_slope, bool blocks_wanted) {
    const Index n = cloth.n;
    start_with_gravity(cloth, water, work.force);
    update_saturation(cloth, phys, water, work.saturation);
    const double* s = work.submerged;
    const bool wet = submerged(phys, n, pos + 2 * n, work.submerged) > 0.0 || !phys.skip_idle;
    const MeshRecords records = fill_records(n, work.cells, blocks_wanted, pos, vel, work.saturation, s, work.force);
    if (blocks_wanted) {
        listed_spring_forces_and_blocks(cloth, phys, records, h, slack_slope, work);
    } else {
        listed_spring_forces(cloth, phys, records);
    }
    Fluid fluids[MESH_FLUIDS];
    Index fluid_count = 0;
    if (wet && !phys.stokes) fluids[fluid_count++] = water_fluid(phys);
    if (phys.air_density > 0.0) fluids[fluid_count++] = air_fluid(phys);  // docs/model.md section 4.4
    if (fluid_count > 0)
        mesh_face_drag(cloth.triangle_count, cloth.triangles, cloth.corner_shares, fluids, fluid_count, h, records,
                       phys.skip_idle);
    store_sums(n, records, work.force, work.diagonal_blocks, work.blocks);
    if (!wet) return;
    buoyancy(n, s, cloth.volume, phys.water_density, GRAVITY, work.force);
    if (phys.stokes) {
        stokes_drag(n, s, cloth.stokes_coefficient, phys.current_x, phys.current_y, vel, work.force);
        if (blocks_wanted)
            stokes_blocks_loop(n, h, cloth.stokes_coefficient, s, work.blocks, work.blocks + n, work.blocks + 2 * n);
    }
    if (blocks_wanted && phys.smooth) add_buoyancy_blocks(cloth, phys, s, h, work.blocks);
}

//: Into work.force (3, n) the drag of one fluid alone on the cloth at pos, vel (the water's: Stokes or face drag
//: in it, `water` true; else the air's face drag), work.submerged holding the particles' submerged fractions.
void drag_alone(const Cloth& cloth, const Physics& phys, Work& work, const double* pos, const double* vel, bool water) {
    const Index n = cloth.n;
    const double* s = work.submerged;
    fill_zero(work.force, 3 * n);
    if (water && phys.stokes) return stokes_drag(n, s, cloth.stokes_coefficient, phys.current_x, phys.current_y, vel,
                                                 work.force);
    const Fluid fluid = water ? water_fluid(phys) : air_fluid(phys);
    if (!is_mesh(cloth)) {
        face_drag(cloth.grid_x, cloth.grid_y, pos, vel, s, fluid, work.force, work.cells, phys.skip_idle);
        return;
    }
    const MeshRecords records = fill_records(n, work.cells, false, pos, vel, work.saturation, s, work.force);
    mesh_face_drag(cloth.triangle_count, cloth.triangles, cloth.corner_shares, &fluid, 1, 0.0, records,
                   phys.skip_idle);
    store_sums(n, records, work.force, nullptr, nullptr);
}

//: The sum over the particles of force (3, n) dotted with the uniform velocity u (m/s).
double dot_uniform(Index n, const double* force, double ux, double uy, double uz) {
    double sum = 0.0;
    for (Index i = 0; i < n; ++i) sum += force[i] * ux + force[n + i] * uy + force[2 * n + i] * uz;
    return sum;
}

}  // namespace

double fluid_drive(const Cloth& cloth, const Physics& phys, Work& work, const double* pos, const double* vel,
                   const double* frame) {
    const Index n = cloth.n;
    const double current[3] = {phys.current_x - frame[0], phys.current_y - frame[1], -frame[2]};
    const double wind[3] = {phys.wind_x - frame[0], phys.wind_y - frame[1], phys.wind_z - frame[2]};
    const bool water_flows = current[0] != 0.0 || current[1] != 0.0 || current[2] != 0.0;
    const bool air_flows = phys.air_density > 0.0 && (wind[0] != 0.0 || wind[1] != 0.0 || wind[2] != 0.0);
    if (!water_flows && !air_flows) return 0.0;
    submerged(phys, n, pos + 2 * n, work.submerged);  // (both fluids' drag reads it)
    double drive = 0.0;
    if (water_flows) {
        drag_alone(cloth, phys, work, pos, vel, true);
        drive += dot_uniform(n, work.force, current[0], current[1], current[2]);
    }
    if (air_flows) {
        drag_alone(cloth, phys, work, pos, vel, false);
        drive += dot_uniform(n, work.force, wind[0], wind[1], wind[2]);
    }
    return drive;
}

double submerged(const Physics& phys, Index n, const double* z, double* out) {
    return submerged_fractions(n, z, phys.water_level, phys.thickness, phys.smooth, out);
}

void forces(const Cloth& cloth, const Physics& phys, Work& work, const double* pos, const double* vel,
            const double* water) {
    if (is_mesh(cloth)) return mesh_forces(cloth, phys, work, pos, vel, water, 0.0, 0.0, false);
    const Index n = cloth.n;
    start_with_gravity(cloth, water, work.force);
    if (cloth.families > 0) {  // (a mesh's listed springs: mesh_forces)
        update_saturation(cloth, phys, water, work.saturation);
        spring_forces(cloth, phys, work.saturation, pos, vel, work.force, work.buf);
    }
    if (submerged(phys, n, pos + 2 * n, work.submerged) > 0.0 || !phys.skip_idle) {
        water_forces(cloth, phys, work, pos, vel, 0.0, false);
    }
    // The air above the water (docs/model.md section 4.4) on the part of each triangle out of it.
    if (phys.air_density > 0.0) add_face_drag(cloth, phys, work, pos, vel, air_fluid(phys), 0.0, false);
}

void forces_and_blocks(const Cloth& cloth, const Physics& phys, Work& work, const double* pos, const double* vel,
                       const double* water, double h, double slack_slope) {
    if (is_mesh(cloth)) return mesh_forces(cloth, phys, work, pos, vel, water, h, slack_slope, true);
    const Index n = cloth.n;
    start_with_gravity(cloth, water, work.force);
    fill_zero(work.diagonal_blocks, 6 * n);
    fill_zero(work.blocks, 6 * n);
    if (cloth.families > 0) {  // (a mesh's listed springs: mesh_forces)
        update_saturation(cloth, phys, water, work.saturation);
        spring_forces_and_blocks(cloth, phys, work.saturation, pos, vel, h, slack_slope, work);
    }
    if (submerged(phys, n, pos + 2 * n, work.submerged) > 0.0 || !phys.skip_idle) {
        water_forces(cloth, phys, work, pos, vel, h, true);
    }
    if (phys.air_density > 0.0) add_face_drag(cloth, phys, work, pos, vel, air_fluid(phys), h, true);
}

}  // namespace wc
