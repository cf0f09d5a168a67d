// The extension module wetcloth._core: every registered family's bindings (convert.hpp).  CMake builds
// it once per instruction set, each under its own name (WETCLOTH_MODULE: _core, _core_x86_64_v3).
#include "convert.hpp"

#ifndef WETCLOTH_MODULE
#define WETCLOTH_MODULE _core
#endif

NB_MODULE(WETCLOTH_MODULE, m) {
    m.doc() = "wetcloth's compiled core (C++17): forces, solvers and the step loop over flat arrays";
    for (auto& bind : wc::py::registry()) bind(m);
}
