// HitSink: a callback for hits with its type erased, so that Tracer::every
// compiles one traversal per window and structure for all its callers (the
// hit counts, the counts once per geometry and the lists of every hit)
// rather than one per caller's lambda. A call through it costs an indirect
// call per hit, which is small beside the traversal that finds the hit.
#pragma once

#include "cpu/cpu_isa.h"
#include "cpu/intersect.h"

#include <memory>

namespace kdrt::detail::inline KDRT_CPU_ISA {

template <class Real>
class HitSink {
public:
    // Calls `f`, which must outlive the sink.
    template <class F>
    explicit HitSink(F& f)
        : target_(std::addressof(f)), call_([](void* target, const Hit<Real>& h) { (*static_cast<F*>(target))(h); }) {}

    void operator()(const Hit<Real>& h) const { call_(target_, h); }

private:
    void* target_;
    void (*call_)(void*, const Hit<Real>&);
};

}  // namespace kdrt::detail::KDRT_CPU_ISA
