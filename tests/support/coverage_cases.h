#pragma once
// Coverage options and meshes for the tests that compare two ways of
// computing coverage (the CPU path against the GPU's, or its host emulation).
#include <vector>

#include "support/slice_cases.h"
#include "support/test_meshes.h"
#include "voxd/voxelize/coverage.h"

namespace voxd::test {

// Every sampling, ray counts from 1 to 8 (k = 8 puts 128 crossings in a
// sphere's columns, past the column sort's insertion sort), a large seed.
inline std::vector<CoverageOptions> coverage_cases() {
  std::vector<CoverageOptions> cases(5);
  cases[0].rays = 4;
  cases[1].rays = 1;
  cases[2].sampling = CoverageSampling::uniform;
  cases[2].rays = 3;
  cases[2].points = 5;
  cases[3].sampling = CoverageSampling::stochastic;
  cases[3].rays = 5;
  cases[3].seed = 0xfedcba9876543210ull;
  cases[4].rays = 8;
  return cases;
}

// The three solids of the slice tests and an open sphere (every 7th
// triangle gone: odd crossing counts, the last one unpaired).
inline std::vector<Mesh> coverage_case_meshes() {
  std::vector<Mesh> ms = slice_case_meshes();
  ms.push_back(punched(make_icosphere({0.05, -0.1, 0.0}, 0.9, 3), 7));
  return ms;
}

}  // namespace voxd::test
