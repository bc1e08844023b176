// HitSink: a callback for hits with its type erased, so that Tracer::every
// compiles one traversal per window and structure for all its callers (the
// hit counts, the counts once per geometry and the lists of every hit)
// rather than one per caller's lambda. A call through it costs an indirect
// call per hit, which is small beside the traversal that finds the hit.
#pragma once

#include "cpu/cpu_isa.h"
#include "cpu/intersect.h"

#include <memory>
#include <type_traits>

namespace kdrt::detail::inline KDRT_CPU_ISA {

template <class Real>
class HitSink {
public:
    // Calls `f`, which must outlive the sink (a const F calls its const operator()).
    template <class F>
        requires(!std::is_same_v<std::remove_cvref_t<F>, HitSink>)
    explicit HitSink(F& f)
        : target_(static_cast<const void*>(std::addressof(f))),
          call_([](const void* target, const Hit<Real>& h) {
              (*static_cast<F*>(const_cast<void*>(target)))(h);
          }) {}

    void operator()(const Hit<Real>& h) const { call_(target_, h); }

private:
    const void* target_;
    void (*call_)(const void*, const Hit<Real>&);
};

}  // namespace kdrt::detail::KDRT_CPU_ISA
