// kdrt._kdrt: the C++ side of the Python package (kdrt/__init__.py is the
// front door). kdrt::Error becomes kdrt.Error (its code in .code); bad
// arguments raise ValueError before kdrt sees them.
#include "arrays.h"
#include "raycasting_scene.h"
#include "render.h"

#include <kdrt/device.h>
#include <kdrt/error.h>
#include <kdrt/version.h>

#include <nanobind/nanobind.h>
#include <nanobind/stl/string.h>

namespace nb = nanobind;

NB_MODULE(_kdrt, m) {
    m.doc() = "kdrt's C++ library: ray queries and rendering on the cpu device and OpenCL devices";
    m.attr("__version__") = KDRT_VERSION_STRING;
    m.attr("INVALID_ID") = 0xFFFFFFFFu;

    static nb::object error = nb::borrow(PyErr_NewExceptionWithDoc(
        "kdrt.Error", "A failure kdrt reports: bad scene, device or OpenCL error, unsupported request.",
        PyExc_RuntimeError, nullptr));
    m.attr("Error") = error;
    nb::register_exception_translator([](const std::exception_ptr& p, void*) {
        try {
            std::rethrow_exception(p);
        } catch (const kdrt::Error& e) {
            nb::object instance = error(nb::str(e.what()));
            instance.attr("code") = nb::str(kdrt::to_string(e.code()));
            PyErr_SetObject(error.ptr(), instance.ptr());
        }
    });

    m.def(
        "list_devices",
        [] {
            nb::list out;
            for (const kdrt::DeviceInfo& d : kdrt::list_devices()) {
                nb::dict info;
                info["id"] = d.id;
                info["platform"] = d.platform;
                info["name"] = d.name;
                info["vendor"] = d.vendor;
                info["type"] = d.type;
                info["compute_units"] = d.compute_units;
                info["global_memory"] = d.global_memory;
                info["fp64"] = d.fp64;
                out.append(info);
            }
            return out;
        },
        "Every device kdrt can run on: 'cpu' and each OpenCL device.");

    kdrt::python::bind_raycasting_scene(m);
    kdrt::python::bind_render(m);
}
