// FunctionRef<R(Args...)>: a callable with its type erased, not owned. A
// template that takes one compiles once for all its callers' lambdas rather
// than once per lambda, at the price of an indirect call per call. Tracer uses
// it where that call is small beside the work around it: the hits of
// Tracer::every, and the leaves of the kd-tree's other traversals.
#pragma once

#include "cpu/cpu_isa.h"

#include <memory>
#include <type_traits>
#include <utility>

namespace kdrt::detail::inline KDRT_CPU_ISA {

template <class Signature>
class FunctionRef;

template <class R, class... Args>
class FunctionRef<R(Args...)> {
public:
    // Calls `f`, which must outlive the reference (a const F calls its const operator()); a
    // FunctionRef returning void drops what `f` returns.
    template <class F>
        requires(!std::is_same_v<std::remove_cvref_t<F>, FunctionRef>)
    explicit FunctionRef(F& f)
        : target_(static_cast<const void*>(std::addressof(f))),
          call_([](const void* target, Args... args) -> R {
              F& callable = *static_cast<F*>(const_cast<void*>(target));
              if constexpr (std::is_void_v<R>) callable(std::forward<Args>(args)...);
              else return callable(std::forward<Args>(args)...);
          }) {}
    // A temporary would be gone before the first call.
    template <class F>
        requires(!std::is_same_v<std::remove_cvref_t<F>, FunctionRef>)
    FunctionRef(const F&&) = delete;

    R operator()(Args... args) const { return call_(target_, std::forward<Args>(args)...); }

private:
    const void* target_;
    R (*call_)(const void*, Args...);
};

}  // namespace kdrt::detail::KDRT_CPU_ISA
