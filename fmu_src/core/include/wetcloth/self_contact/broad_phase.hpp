// Candidate pairs from a spatial hash, kept while the cloth's motion allows (port of
// bf41571:fmu_src/wetcloth/kernels/self_contact/broad_phase.py; see its docstring for the reasoning).
//
// A candidate list holds every point-triangle and edge-edge pair whose elements were closer than
// reach = thickness + 2 margin at the *reference* positions it was built from.  It stays valid while no pair
// outside it can come closer than the thickness, judged tier by tier (tiers.hpp): each tier's windows may
// deviate from a rigid motion of their reference positions by the tier's allowance (or a coarser tier's
// windows by that much) along the step's motion.  The finest tier's pairs are the fabric's neighbours, and
// its allowance is the margin (on a mesh whose smallest triangles cap the margin, each particle's own, at least
// the margin: half what its nearest pair left out has beyond the thickness; ContactLists::particle_allowances);
// a coarser tier's pairs lie farther apart in the rest sheet, and its
// allowance is the widest that keeps them out of the list (its nearest pair at the reference positions, out
// of reach), up to what their distance in the rest sheet leaves room for, and at least the margin (infinite
// for a tier without pairs, whose finer tier's one window holds the whole sheet).  The list
// and the allowances depend on the reference positions and the margin alone (its pairs ascend, whatever the
// hash), so a run restored from a snapshot of those two rebuilds exactly the same list.
//
// The lists live in ContactLists (core.hpp): point_triangle and edge_edge (2, count), first row then
// second row.  While a list is searched they hold records (first, second, bits of the distance), three
// Index values per pair; scratch holds the boxes, index_scratch the hash.
#pragma once

#include "wetcloth/core.hpp"

namespace wc::self_contact {

//: A list whose margin is more than this many times what the current step needs is rebuilt (expired).
inline constexpr double LOOSE = 4.0;
//: The reach of a list tried after an empty one, as a fraction of the rest sheet's nearest non-adjacent
//: elements' distance (Contact::rest_gap): room for the sheet to be compressed by a tenth without
//: candidates (0.9 rather than 0.7: fewer rebuilds of empty lists, docs/benchmarks.md).
inline constexpr double WIDE_REACH = 0.9;
//: The fraction of the finest tier's windows not shown free of pairs (flat_windows.hpp) beyond which a list's
//: build searches every pair instead of theirs: searching most windows' elements costs about the whole
//: search, and the coarser tiers' pairs are then searched too.
inline constexpr double MOST_UNPROVEN = 0.5;
//: The most hash cells a box spans (at most 9 along each axis, 10 if rounding puts both ends on a cell's
//: boundary).
inline constexpr Index MOST_CELLS = 10 * 10 * 10;

//: How many candidate pairs the current list holds.
inline Index candidate_count(const Contact& contact) {
    return contact.lists->point_triangle_count() + contact.lists->edge_edge_count();
}

//: Whether the candidate list is valid for the straight-line motion from x0 to x1 (both (3, n)): for each
//: tier, its windows' deviation from a rigid motion of their reference positions (or a coarser tier's) is
//: at most the tier's allowance.  False if a position is not finite.
bool covers(const Contact& contact, Index n, const double* x0, const double* x1);

//: Whether the list must be rebuilt for the step from x0 to x1: it does not hold (covers); or its margin is
//: over LOOSE times what a list built for the step would get; or it is empty, holds only window by window
//: (the cloth has turned since its reference) and the cloth barely moves (a list built now holds through
//: the translation alone, the cheapest check).
bool expired(const Contact& contact, Index n, const double* x0, const double* x1);

//: A new list valid for the whole step from x0 to x1 (the reference is the midpoint; the margin four times
//: the step's deviation from the midpoint in the finest tier's windows, or in a coarser tier's if less, at
//: least Contact::least_margin; after an empty list, as wide as keeps it empty; larger if a coarser tier's
//: allowance could not hold the step).  Returns false (and builds nothing) if the step is not finite.
bool rebuild_for_step(Contact& contact, Index n, double thickness, const double* x0, const double* x1);

//: Build the lists from contact.reference for the widest margin from `least` to `widest` (m) whose lists
//: are empty, or for `least` if none is (searched at `widest` and narrowed: the same lists as build() for
//: that margin); keep that margin, and the coarser tiers' allowances.
void build_widest(Contact& contact, Index n, double thickness, double least, double widest);

//: build_widest() over the tiers' cells already cut (prepare_tiers).
void build_lists(Contact& contact, Index n, double thickness, double least, double widest);

}  // namespace wc::self_contact
