// The extension module wetcloth._core: every registered family's bindings (convert.hpp).
#include "convert.hpp"

NB_MODULE(_core, m) {
    m.doc() = "wetcloth's compiled core (C++17): forces, solvers and the step loop over flat arrays";
    for (auto& bind : wc::py::registry()) bind(m);
}
