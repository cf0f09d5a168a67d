// The grip (docs/model.md section 6.4): the pinned particles follow a prescribed displacement, from the
// inputs grip_x, grip_y, grip_z and from keys in time.
#pragma once
#include "wetcloth/core.hpp"

namespace wc {

//: Below this (m) the inputs' part of the displacement counts as arrived: the grip holds still.
inline constexpr double GRIP_RESOLUTION = 1e-9;

//: One step's motion of the grip.  `acts`: there are pinned particles and the grip displaces them (or
//: will); `moving`: it moves in this step, or keys lie ahead; `end` (3, m) its displacement at the step's
//: end; `rate` (3, m/s) its velocity over the step.
struct GripMove {
    bool acts = false;
    bool moving = false;
    double end[3] = {0.0, 0.0, 0.0};
    double rate[3] = {0.0, 0.0, 0.0};
};

//: The keys' displacement d (3, m) at time t s: 0 at t = 0, linear to the first key and between keys
//: (rows time, x, y, z of phys.grip_keys), the last key's after it; 0 without keys.
void key_displacement(const Physics& phys, double t, double* d);

//: The grip's move over a step of h s from time t s, `remaining` s before the end of the interval being
//: advanced through.  Its displacement is the keys' plus the inputs' part, which goes linearly from where
//: it is (the pinned particles' displacement from phys.grip_origin, pos (3, n) at the step's start, less
//: the keys') to (grip_x, grip_y, grip_z) at the interval's end.  Pinned: free 0 and held 0.
GripMove grip_move(Index n, const Physics& phys, const double* free, const double* held, const double* pos,
                   double t, double h, double remaining);

//: Put the pinned particles (free 0, held 0) at grip_origin + move.end (pos (3, n), unless pos is null)
//: with velocity move.rate (vel (3, n)); nothing unless the grip acts.
void place_grip(Index n, const Physics& phys, const GripMove& move, const double* free, const double* held,
                double* pos, double* vel);

}  // namespace wc
