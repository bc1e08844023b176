// numpy arrays in and out of the module: shape checks that raise ValueError
// naming the argument, and new arrays that own their memory.
#pragma once

#include <nanobind/nanobind.h>
#include <nanobind/ndarray.h>

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace kdrt::python {

namespace nb = nanobind;

// A read-only, C-contiguous CPU array of T, as the Python layer (kdrt/__init__.py) hands it over.
template <class T>
using In = nb::ndarray<const T, nb::c_contig, nb::device::cpu>;

// A new numpy array of `shape`, its memory uninitialised and owned by the array.
template <class T>
nb::ndarray<nb::numpy, T> new_array(const std::vector<std::size_t>& shape) {
    std::size_t n = 1;
    for (std::size_t s : shape) n *= s;
    T* data = new T[n == 0 ? 1 : n];
    nb::capsule owner(data, [](void* p) noexcept { delete[] static_cast<T*>(p); });
    return nb::ndarray<nb::numpy, T>(data, shape.size(), shape.data(), owner);
}

inline std::string shape_text(const std::vector<std::size_t>& shape) {
    std::string s = "(";
    for (std::size_t i = 0; i < shape.size(); ++i) s += (i ? ", " : "") + std::to_string(shape[i]);
    return s + (shape.size() == 1 ? ",)" : ")");
}

template <class A>
std::vector<std::size_t> shape_of(const A& a) {
    std::vector<std::size_t> shape(a.ndim());
    for (std::size_t i = 0; i < a.ndim(); ++i) shape[i] = a.shape(i);
    return shape;
}

// The leading shape of an array of shape (..., last); ValueError naming `what` otherwise.
template <class A>
std::vector<std::size_t> leading_shape(const A& a, std::size_t last, const char* what) {
    std::vector<std::size_t> shape = shape_of(a);
    if (shape.empty() || shape.back() != last)
        throw nb::value_error((std::string(what) + " must have shape (..., " + std::to_string(last) + "), got " +
                               shape_text(shape))
                                  .c_str());
    shape.pop_back();
    return shape;
}

inline std::vector<std::size_t> with_last(std::vector<std::size_t> shape, std::size_t last) {
    shape.push_back(last);
    return shape;
}

inline std::size_t count_of(const std::vector<std::size_t>& shape) {
    std::size_t n = 1;
    for (std::size_t s : shape) n *= s;
    return n;
}

}  // namespace kdrt::python
