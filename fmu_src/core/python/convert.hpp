// Views of the Python package's bundles (named tuples of NumPy arrays and numbers) as the core's
// structs, by field name.  An array is taken as it is, never converted: a copy would leave the
// core writing into a temporary.  A field of the wrong type, layout or size is a TypeError naming it.
#pragma once

#include <nanobind/nanobind.h>
#include <nanobind/ndarray.h>

#include <functional>
#include <string>
#include <vector>

#include "wetcloth/core.hpp"

namespace wc::py {

namespace nb = nanobind;
using namespace nanobind::literals;

//: The array in `field` of `bundle` (C-contiguous, of T, at least `count` elements if count >= 0).
template <class T>
T* array(nb::handle bundle, const char* field, Index count = -1) {
    nb::object value = bundle.attr(field);
    nb::ndarray<T, nb::c_contig, nb::device::cpu> a;
    if (!nb::try_cast(value, a, false)) {
        throw nb::type_error(("field '" + std::string(field) + "': expected a C-contiguous array of " +
                              (std::is_same_v<std::remove_const_t<T>, double>  ? "float64"
                               : std::is_same_v<std::remove_const_t<T>, float> ? "float32"
                               : std::is_same_v<std::remove_const_t<T>, bool>  ? "bool"
                               : std::is_same_v<std::remove_const_t<T>, Column> ? "int32" : "int64"))
                                 .c_str());
    }
    if (count >= 0 && static_cast<Index>(a.size()) < count) {
        throw nb::type_error(("field '" + std::string(field) + "': expected at least " + std::to_string(count) +
                              " elements, got " + std::to_string(a.size()))
                                 .c_str());
    }
    return a.data();
}

//: A plain array argument (C-contiguous, of T, at least `count` elements if count >= 0).
template <class T>
T* argument(nb::handle value, const char* name, Index count = -1) {
    nb::ndarray<T, nb::c_contig, nb::device::cpu> a;
    if (!nb::try_cast(value, a, false)) {
        throw nb::type_error(("argument '" + std::string(name) + "': expected a C-contiguous array").c_str());
    }
    if (count >= 0 && static_cast<Index>(a.size()) < count) {
        throw nb::type_error(("argument '" + std::string(name) + "': expected at least " + std::to_string(count) +
                              " elements, got " + std::to_string(a.size()))
                                 .c_str());
    }
    return a.data();
}

//: The number of elements of a plain array argument.
inline Index size_of(nb::handle value) {
    nb::ndarray<nb::c_contig, nb::device::cpu> a;
    if (!nb::try_cast(value, a, false)) throw nb::type_error("expected a C-contiguous array");
    return static_cast<Index>(a.size());
}

//: Python's truth of a flag argument (bool, numpy.bool_, int), as numba takes it.
inline bool truth(nb::handle value) {
    const int r = PyObject_IsTrue(value.ptr());
    if (r < 0) throw nb::python_error();
    return r != 0;
}

template <class T>
T number(nb::handle bundle, const char* field) {
    return nb::cast<T>(bundle.attr(field));
}

Cloth cloth_from(nb::handle cloth);
Physics physics_from(nb::handle phys);
ColliderMeshes meshes_from(nb::handle meshes);
Control control_from(nb::handle control);
Work work_from(nb::handle work, const Cloth& cloth);
Solver solver_from(nb::handle solver, Index n);
Hierarchy hierarchy_from(nb::handle grid);
Algebraic algebraic_from(nb::handle algebraic);
Plane plane_from(nb::handle plane, Index n);
//: The lists are the caller's (kept with the views as long as they are used).
Contact contact_from(nb::handle contact, Index n, ContactLists* lists);
Buffers buffers_from(nb::handle buf, Index n);

//: Bindings register themselves (WETCLOTH_BINDINGS below) and the module runs them all, so that each
//: family's bindings live beside nothing else.
std::vector<std::function<void(nb::module_&)>>& registry();

struct Registrar {
    explicit Registrar(std::function<void(nb::module_&)> bind) { registry().push_back(std::move(bind)); }
};

}  // namespace wc::py

#define WETCLOTH_CONCAT_(a, b) a##b
#define WETCLOTH_CONCAT(a, b) WETCLOTH_CONCAT_(a, b)
//: WETCLOTH_BINDINGS(m) { m.def(...); }: bindings added to the module `wetcloth._core`.
#define WETCLOTH_BINDINGS(m)                                                                        \
    static void WETCLOTH_CONCAT(wetcloth_bind_, __LINE__)(nanobind::module_ & m);                    \
    static ::wc::py::Registrar WETCLOTH_CONCAT(wetcloth_registrar_, __LINE__){                       \
        WETCLOTH_CONCAT(wetcloth_bind_, __LINE__)};                                                  \
    static void WETCLOTH_CONCAT(wetcloth_bind_, __LINE__)(nanobind::module_ & m)
