// kdrt.Scene, kdrt.load_scene and kdrt.render: scene files and model files
// rendered from Python into numpy arrays, cancellable with Ctrl-C.
#pragma once

#include <nanobind/nanobind.h>

namespace kdrt::python {

void bind_render(nanobind::module_& m);

}  // namespace kdrt::python
