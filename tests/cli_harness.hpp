#pragma once
// Runs the `breccia` command (BRECCIA_CLI) from tests and reads what it writes.
#include <sys/wait.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

namespace breccia::testing {

struct Result {
  int code;
  std::string out;
};

inline Result run_with_prefix(const std::string& prefix, const std::string& args) {
  const std::string cmd = prefix + std::string(BRECCIA_CLI) + " " + args + " 2>&1";
  Result r{0, {}};
  FILE* p = popen(cmd.c_str(), "r");
  char buf[4096];
  while (std::size_t n = fread(buf, 1, sizeof buf, p)) r.out.append(buf, n);
  const int status = pclose(p);
  r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return r;
}

inline Result run(const std::string& args) {
  return run_with_prefix("", args);
}

// The [experiment] of a tiny calibration: a generated 3 x 3 x 6 mm prism (about 330 grains),
// packed and built in about a second.
inline const std::string kTinyCalibrationExperiment =
    "[experiment]\n[experiment.engine]\nthreads = 1\ndensity_scaling = 10.0\n"
    "[experiment.material]\npreset = \"custom\"\n[experiment.sample]\nwidth = 3e-3\n"
    "depth = 3e-3\nheight = 6e-3\nradius_min = 0.22e-3\nradius_max = 0.36e-3\n"
    "[experiment.contact]\nlaw = \"hertz_mindlin\"\nshear_modulus = 29e9\n"
    "poisson_ratio = 0.33\nfriction = 0.4\n[experiment.bond]\nmodulus = 8e9\n"
    "tensile_strength = 30e6\ncohesion = 60e6\n";

inline std::string last_line(const std::string& s) {
  std::string t = s;
  while (!t.empty() && t.back() == '\n') t.pop_back();
  const auto nl = t.rfind('\n');
  return nl == std::string::npos ? t : t.substr(nl + 1);
}

inline std::string read(const std::filesystem::path& p) {
  std::ifstream in(p);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

}  // namespace breccia::testing
