#pragma once
// VOXD_HD marks the engine's arithmetic that is written once and compiled
// twice: by the C++ compiler into the CPU paths and by nvcc into the CUDA
// kernels (core/src/cuda/), so both run the same IEEE operations in the same
// order (see slice_shading.h for what keeps the bits equal).
#if defined(__CUDACC__)
#define VOXD_HD __host__ __device__
#else
#define VOXD_HD
#endif
