// Self-collision for Python (tests and parity checks): resolve, build, build_widest, invalidate, covers and
// deviation over the Python Contact bundle, with its candidate lists in a ContactState (the C++
// ContactLists).  The lists are taken from the `lists` argument or, when it is None, from the bundle's
// `pairs` field if that holds a ContactState, so the kernels keep numba's signatures where the bundle
// carries one.
#include <nanobind/stl/string.h>
#include <nanobind/stl/vector.h>

#include <algorithm>
#include <cstring>

#include "convert.hpp"
#include "wetcloth/self_contact.hpp"
#include "wetcloth/self_contact/broad_phase.hpp"
#include "wetcloth/self_contact/flat_windows.hpp"
#include "wetcloth/self_contact/tiers.hpp"

namespace wc::py {
namespace {

//: One Python Contact's candidate lists, indexable like numba's typed list: [0] the point-triangle pairs,
//: [1] the edge-edge pairs, each (2, count) int64 (copies).
struct ContactState {
    ContactLists lists;

    std::vector<Index>& kind(Index k) {
        if (k == 0) return lists.point_triangle;
        if (k == 1) return lists.edge_edge;
        throw nb::index_error("ContactState: 0 (point-triangle) or 1 (edge-edge)");
    }
};

nb::object rows_copy(const std::vector<Index>& rows) {
    const std::size_t count = rows.size() / 2;
    Index* data = new Index[std::max<std::size_t>(rows.size(), 1)];
    std::copy(rows.begin(), rows.end(), data);
    nb::capsule owner(data, [](void* p) noexcept { delete[] static_cast<Index*>(p); });
    const std::size_t shape[2] = {2, count};
    return nb::cast(nb::ndarray<nb::numpy, Index, nb::ndim<2>>(data, 2, shape, owner));
}

ContactLists* lists_of(nb::handle contact, nb::handle lists) {
    nb::handle source = lists.is_none() ? nb::handle(contact.attr("pairs")) : lists;
    ContactState* state = nullptr;
    if (!nb::try_cast(source, state, false) || state == nullptr) {
        throw nb::type_error("self-collision: pass a ContactState as `lists` (or hold one in Contact.pairs)");
    }
    return &state->lists;
}

Index particles_of(nb::handle contact) { return size_of(contact.attr("reference")) / 3; }

}  // namespace
}  // namespace wc::py

WETCLOTH_BINDINGS(m) {
    using namespace wc;
    using namespace wc::py;
    using namespace nb::literals;

    nb::class_<ContactState>(m, "ContactState",
                             "Self-collision's candidate lists (C++ ContactLists): [0] point-triangle, [1] edge-edge "
                             "pairs, each (2, count) int64")
        .def(nb::init<>())
        .def_prop_ro("point_triangle", [](ContactState& s) { return rows_copy(s.lists.point_triangle); })
        .def_prop_ro("edge_edge", [](ContactState& s) { return rows_copy(s.lists.edge_edge); })
        .def_prop_ro("point_triangle_count", [](ContactState& s) { return s.lists.point_triangle_count(); })
        .def_prop_ro("edge_edge_count", [](ContactState& s) { return s.lists.edge_edge_count(); })
        .def_prop_ro("allowances", [](ContactState& s) { return s.lists.allowances; },
                     "Each tier's allowance (m) of the last list built (empty before one is)")
        .def_prop_ro("resting", [](ContactState& s) { return s.lists.resting; },
                     "What each particle held on a layer rests on, (n, 3) flattened: up to three particles, -1 padding")
        .def_prop_ro("resting_normal", [](ContactState& s) { return s.lists.resting_normal; },
                     "The unit normal from each held particle's support to it, (n, 3) flattened")
        .def_prop_ro("particle_allowances", [](ContactState& s) { return s.lists.particle_allowances; },
                     "Each particle's own allowances (m) in the finest tier of the last list built, (2, n) "
                     "flattened: for its pairs that fit a window of the fine tier, then for the others (empty if "
                     "they have none)")
        .def(
            "fine_cells",
            [](ContactState& s, Index n) {
                const self_contact::Tier t = self_contact::tier_in(s.lists.tiers, n, self_contact::FINE_TIER);
                std::vector<Index> out(static_cast<std::size_t>(2 * n));
                for (Index i = 0; i < n; ++i) out[i] = t.cx(i), out[n + i] = t.cy(i);
                return out;
            },
            nb::arg("n"),
            "Each of the n particles' cell of the fine tier of the last list built, (2, n) flattened: along the "
            "rest sheet's x, then y (a pair fits one of its windows where its cells span at most WINDOW)")
        .def("__len__", [](ContactState&) { return 2; })
        .def("__getitem__", [](ContactState& s, Index k) { return rows_copy(s.kind(k)); })
        .def("__setitem__", [](ContactState& s, Index k, nb::ndarray<const Index, nb::ndim<2>, nb::device::cpu> a) {
            if (a.shape(0) != 2) throw nb::value_error("ContactState: pairs are (2, count)");
            std::vector<Index>& rows = s.kind(k);
            const std::size_t count = a.shape(1);
            rows.resize(2 * count);
            for (std::size_t r = 0; r < 2; ++r)
                for (std::size_t j = 0; j < count; ++j)
                    rows[r * count + j] = a.data()[r * a.stride(0) + j * a.stride(1)];
        });

    m.def(
        "resolve",
        [](nb::handle contact, double thickness, double floor_z, double blow_up_speed, nb::handle mass,
           nb::handle free, nb::handle x0, nb::handle x1, nb::handle v1, double h, nb::handle lists,
           bool layers_solved) {
            const Index n = size_of(x0) / 3;
            Contact c = contact_from(contact, n, lists_of(contact, lists));
            c.layers_solved = layers_solved;
            return resolve(c, thickness, floor_z, blow_up_speed, n, argument<const double>(mass, "mass", n),
                           argument<const double>(free, "free", n), argument<const double>(x0, "x0", 3 * n),
                           argument<double>(x1, "x1", 3 * n), argument<double>(v1, "v1", 3 * n), h);
        },
        "contact"_a, "thickness"_a, "floor_z"_a, "blow_up_speed"_a, "mass"_a, "free"_a, "x0"_a, "x1"_a, "v1"_a, "h"_a,
        "lists"_a = nb::none(), "layers_solved"_a = false,
        "The self-collision stage of one step of h s from x0 to x1 (x1, v1 changed in place); whether it changed "
        "them.  layers_solved: the step's solve held the listed pairs (a fixed step's supports), so pairs it left "
        "at least KEPT_FRACTION of the thickness apart are left.");
    m.def(
        "build",
        [](nb::handle contact, double thickness, double margin, nb::handle lists) {
            const Index n = particles_of(contact);
            Contact c = contact_from(contact, n, lists_of(contact, lists));
            build(c, n, thickness, margin);
        },
        "contact"_a, "thickness"_a, "margin"_a, "lists"_a = nb::none(),
        "Build the candidate lists from contact.reference for margin (m) and keep the margin.");
    m.def(
        "build_widest",
        [](nb::handle contact, double thickness, double least, double widest, nb::handle lists) {
            const Index n = particles_of(contact);
            Contact c = contact_from(contact, n, lists_of(contact, lists));
            self_contact::build_widest(c, n, thickness, least, widest);
        },
        "contact"_a, "thickness"_a, "least"_a, "widest"_a, "lists"_a = nb::none(),
        "Build the candidate lists for the widest margin from least to widest (m) whose lists are empty.");
    m.def(
        "hold_on_layers",
        [](nb::handle contact, double thickness, nb::handle pos, nb::handle vel, nb::handle free, nb::handle held,
           nb::handle lists) {
            const Index n = particles_of(contact);
            Contact c = contact_from(contact, n, lists_of(contact, lists));
            return hold_on_layers(c, thickness, n, argument<const double>(pos, "pos", 3 * n),
                                  argument<const double>(vel, "vel", 3 * n), argument<double>(free, "free", n),
                                  argument<double>(held, "held", n));
        },
        "contact"_a, "thickness"_a, "pos"_a, "vel"_a, "free"_a, "held"_a, "lists"_a = nb::none(),
        "Hold the free particles at rest on a still layer (free and held changed in place); how many.");
    m.def(
        "release_sliding",
        [](nb::handle contact, nb::handle force, nb::handle free, nb::handle held, nb::handle lists) {
            const Index n = particles_of(contact);
            Contact c = contact_from(contact, n, lists_of(contact, lists));
            return release_sliding(c, n, argument<const double>(force, "force", 3 * n), argument<double>(free, "free", n),
                                   argument<double>(held, "held", n));
        },
        "contact"_a, "force"_a, "free"_a, "held"_a, "lists"_a = nb::none(),
        "Release the layer-held particles the force (3, n) N slides off their support; how many.");
    m.def(
        "hold_within_friction",
        [](nb::handle contact, double thickness, nb::handle pos, nb::handle vel, nb::handle force, nb::handle free,
           nb::handle held, nb::handle lists) {
            const Index n = particles_of(contact);
            Contact c = contact_from(contact, n, lists_of(contact, lists));
            return hold_within_friction(c, thickness, n, argument<const double>(pos, "pos", 3 * n),
                                        argument<const double>(vel, "vel", 3 * n),
                                        argument<const double>(force, "force", 3 * n),
                                        argument<double>(free, "free", n), argument<double>(held, "held", n));
        },
        "contact"_a, "thickness"_a, "pos"_a, "vel"_a, "force"_a, "free"_a, "held"_a, "lists"_a = nb::none(),
        "After release_sliding: hold the free particles another still element holds within friction; how many.");
    m.def(
        "unproven_windows",
        [](nb::handle contact, nb::handle x, double reach, nb::handle lists) {
            const Index n = particles_of(contact);
            Contact c = contact_from(contact, n, lists_of(contact, lists));
            self_contact::prepare_tiers(c, n);
            self_contact::FlatWindows flat(c, n, argument<const double>(x, "x", 3 * n), reach);
            std::vector<char> inside(static_cast<std::size_t>(n), 1);
            Index windows = 0;
            const Index count = flat.judged() ? flat.unproven(inside, windows) : -1;
            const int through = flat.judged() ? flat.shown_through() : 0;
            return nb::make_tuple(count, windows, std::vector<Index>(inside.begin(), inside.end()), through);
        },
        "contact"_a, "x"_a, "reach"_a, "lists"_a = nb::none(),
        "How many windows of the finest tier at x (3, n) are not shown to hold no pair within reach (m; -1: none "
        "can be), of how many, each particle's lying in one of them (1) or not (0), and the coarsest local tier "
        "through which every window is shown.");
    m.def(
        "invalidate",
        [](nb::handle contact, nb::handle lists) {
            const Index n = particles_of(contact);
            Contact c = contact_from(contact, n, lists_of(contact, lists));
            invalidate(c);
        },
        "contact"_a, "lists"_a = nb::none(), "Forget the candidate list: margin 0, no pairs.");
    m.def(
        "covers",
        [](nb::handle contact, nb::handle x0, nb::handle x1, nb::handle lists) {
            const Index n = particles_of(contact);
            Contact c = contact_from(contact, n, lists_of(contact, lists));
            return self_contact::covers(c, n, argument<const double>(x0, "x0", 3 * n),
                                        argument<const double>(x1, "x1", 3 * n));
        },
        "contact"_a, "x0"_a, "x1"_a, "lists"_a = nb::none(),
        "Whether the candidate list (built first) holds for the straight-line motion from x0 to x1.");
    m.def(
        "deviation",
        [](nb::handle contact, int tier, nb::handle x0, nb::handle x1, nb::handle lists) {
            const Index n = particles_of(contact);
            if (tier < 0 || tier >= self_contact::TIERS) throw nb::index_error("deviation: no such tier");
            Contact c = contact_from(contact, n, lists_of(contact, lists));
            self_contact::prepare_tiers(c, n);
            return self_contact::deviation(c, n, tier, c.reference, argument<const double>(x0, "x0", 3 * n),
                                           argument<const double>(x1, "x1", 3 * n));
        },
        "contact"_a, "tier"_a, "x0"_a, "x1"_a, "lists"_a = nb::none(),
        "The largest deviation (m) of tier's windows, moving from x0 to x1, from a rigid motion of "
        "contact.reference.");
    m.attr("TIERS") = self_contact::TIERS;
    m.attr("WIDE_REACH") = self_contact::WIDE_REACH;
    m.attr("WINDOW") = self_contact::WINDOW;
    m.attr("LOOSE") = self_contact::LOOSE;
    m.attr("ZONE_ROWS") = ZONE_ROWS;
}
