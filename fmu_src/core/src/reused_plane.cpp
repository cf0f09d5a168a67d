// The adaptive steps' reused Jacobian preconditioner (reused_plane.hpp).
#include "wetcloth/reused_plane.hpp"

#include <algorithm>

#include "wetcloth/plane.hpp"

namespace wc {

namespace {

//: A view of the Jacobian's parts in source (reused_source_size's layout after pos and mass).
Work source_work(ReusedPlane& reused, Index n, Index families) {
    Work work;
    double* s = reused.source.data() + 4 * n;
    work.blocks = s;
    work.direction = s + 6 * n;
    work.along = work.direction + 3 * families * n;
    work.across = work.along + families * n;
    return work;
}

//: The in-plane systems from source, projected on the frame of its positions; the plane then applies
//: them in the frame it shares with Core::plane.
Index build_from_source(ReusedPlane& reused, const Cloth& cloth) {
    const Index n = cloth.n;
    const double* pos = reused.source.data();
    double* applied = reused.plane.frame;
    reused.plane.frame = reused.frame_at_build.data();
    follow_cloth(reused.plane, cloth, pos);
    const Index result = set_systems_from_jacobian(reused.plane, cloth, pos + 3 * n,
                                                   source_work(reused, n, cloth.families), NORMAL);
    reused.plane.frame = applied;
    return result;
}

}  // namespace

void attach_reused(ReusedPlane& reused, const Plane& plane, Index n) {
    const Index size = plane.grid.size;
    const Index band = COMPONENTS * plane.coarse_n * (plane.kd + 1);
    reused.storage.assign(static_cast<std::size_t>(9 * COMPONENTS * size + COMPONENTS * size + 2 * band + 4), 0.0);
    reused.frame_at_build.assign(static_cast<std::size_t>(9 * n), 0.0);
    reused.source.assign(static_cast<std::size_t>(reused_source_size(n, plane.families)), 0.0);
    reused.rule.fill(0.0);
    Plane& p = reused.plane;
    p = plane;  // frame, normal diagonal, scratch and fixed arrays shared
    double* at = reused.storage.data();
    auto take = [&at](Index count) {
        double* start = at;
        at += count;
        return start;
    };
    p.grid.coef = take(9 * COMPONENTS * size);
    p.grid.inverse_diagonal = take(COMPONENTS * size);
    p.bands = take(band);
    p.rows = take(band);
    p.reference = take(4);
    reused.single_storage.assign(static_cast<std::size_t>(10 * COMPONENTS * size), 0.0f);
    p.grid.single_coef = reused.single_storage.data();
    p.grid.single_inverse_diagonal = p.grid.single_coef + 9 * COMPONENTS * size;
}

bool reuse_expired(const ReusedPlane& reused, double scale, double last_solve) {
    const auto& rule = reused.rule;
    if (rule[REUSED_BUILT] == 0.0) return true;
    const double ratio = scale / rule[REUSED_SCALE];
    if (!(1.0 / REUSE_SCALE <= ratio && ratio <= REUSE_SCALE)) return true;
    return rule[REUSED_FIRST_SOLVE] > 0.0 && last_solve > REUSE_FLOOR &&
           last_solve > REUSE_RISE * rule[REUSED_FIRST_SOLVE];
}

Index build_reused(ReusedPlane& reused, const Cloth& cloth, const double* mass, const Work& work, const double* pos,
                   double scale) {
    const Index n = cloth.n, families = cloth.families;
    double* s = reused.source.data();
    std::copy(pos, pos + 3 * n, s);
    std::copy(mass, mass + n, s + 3 * n);
    const Work kept = source_work(reused, n, families);
    std::copy(work.blocks, work.blocks + 6 * n, kept.blocks);
    std::copy(work.direction, work.direction + 3 * families * n, kept.direction);
    std::copy(work.along, work.along + families * n, kept.along);
    std::copy(work.across, work.across + families * n, kept.across);
    reused.rule = {1.0, scale, 0.0};
    return build_from_source(reused, cloth);
}

void rebuild_reused(ReusedPlane& reused, const Cloth& cloth) {
    if (reused.rule[REUSED_BUILT] != 0.0) build_from_source(reused, cloth);
}

void count_reused_solve(ReusedPlane& reused, Index iterations) {
    if (reused.rule[REUSED_FIRST_SOLVE] == 0.0) {
        reused.rule[REUSED_FIRST_SOLVE] = static_cast<double>(std::max<Index>(iterations, 1));
    }
}

}  // namespace wc
