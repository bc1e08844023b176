// Which x86 instruction set the cpu device's hot loops run in. The traversal,
// intersection and shading templates (the cpu/ headers that include this one)
// are compiled twice: for x86-64's baseline (SSE2) and, with GCC or Clang on
// x86-64, for AVX2 + FMA + BMI (x86-64-v3, in cpu_tracing_avx2.cpp). Each copy
// lives in its own inline namespace, KDRT_CPU_ISA, so the linker never mixes
// them up; the renderer picks one at run time, as Embree does. The build's
// -ffp-contract=off keeps fused multiply-adds out, so both give the same bits.
#pragma once

#ifndef KDRT_CPU_ISA
#define KDRT_CPU_ISA isa_baseline
#endif
// The copy's vector register width: 16 (SSE2) or 32 (AVX2). The target
// pragmas do not define __AVX2__, so the AVX2 copy's file says it.
#ifndef KDRT_CPU_VECTOR_BYTES
#define KDRT_CPU_VECTOR_BYTES 16
#endif

// The AVX2 copy: GCC and Clang (their target pragmas, which keep the ISA but
// not the tuning, so baseline helpers from glm and std:: still inline into it).
#if defined(__GNUC__) && defined(__x86_64__)
#define KDRT_CPU_HAS_AVX2_COPY 1
#else
#define KDRT_CPU_HAS_AVX2_COPY 0
#endif

namespace kdrt::detail {

enum class CpuIsa { Baseline, Avx2 };

// The best copy this processor runs; the environment variable
// KDRT_CPU_ISA=baseline forces the baseline one (tests and measurements).
CpuIsa cpu_isa();
const char* cpu_isa_name(CpuIsa isa);

}  // namespace kdrt::detail
