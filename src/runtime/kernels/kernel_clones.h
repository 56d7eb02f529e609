// SHTOOL_KERNEL_CLONES: on x86-64 builds with GCC, a generated kernel marked with it is
// compiled twice, for the baseline and for x86-64-v3 (AVX2, FMA), and the loader picks
// the second on CPUs that have those (an ifunc, as FFTW picks its codelets): a baseline
// build runs the faster code where it can, without the user adding -march flags. GCC
// fuses a * b + c in the v3 copy (C++ contracts by default; the tripling kernels' file
// also says -ffp-contract=fast), so results differ from the baseline copy by rounding:
// only for kernels whose results no inline code in the user's build must reproduce bit
// for bit (not the rotation kernels: three interleaved channels equal three apply() calls exactly, and
// their order-2/3 paths are inline).
#pragma once

// SHTOOL_NO_KERNEL_CLONES builds the baseline copy alone (test_tripling_baseline).
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__) && defined(__linux__) && \
    !defined(SHTOOL_NO_KERNEL_CLONES)
#define SHTOOL_KERNEL_CLONES __attribute__((target_clones("arch=x86-64-v3", "default")))
#else
#define SHTOOL_KERNEL_CLONES
#endif
