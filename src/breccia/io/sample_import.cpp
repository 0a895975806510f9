#include "breccia/io/sample_import.hpp"

#include <charconv>
#include <cmath>
#include <fstream>
#include <sstream>

#include "breccia/core/error.hpp"
#include "breccia/core/format.hpp"

namespace breccia {

namespace {

std::vector<std::string> split(const std::string& line) {
  std::vector<std::string> out;
  std::string cur;
  for (char c : line) {
    if (c == '#') break;
    if (c == ',' || c == ' ' || c == '\t' || c == '\r' || c == ';') {
      if (!cur.empty()) out.push_back(cur);
      cur.clear();
    } else {
      cur += c;
    }
  }
  if (!cur.empty()) out.push_back(cur);
  return out;
}

bool parse_real(const std::string& t, double& v) {
  const auto r = std::from_chars(t.data(), t.data() + t.size(), v);
  return r.ec == std::errc() && r.ptr == t.data() + t.size() && std::isfinite(v);
}

std::ifstream open(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw InputError(path, "", "", "cannot open the sample file");
  return in;
}

}  // namespace

GeometryData read_xyzr_table(const std::string& path, Dimension dim, double density,
                             double thickness) {
  std::ifstream in = open(path);
  GeometryData g;
  g.dimension = dim;
  g.thickness = dim == Dimension::Two ? thickness : 1.0;
  std::string line;
  std::size_t n = 0;
  bool header_seen = false;
  while (std::getline(in, line)) {
    ++n;
    const auto tok = split(line);
    if (tok.empty()) continue;
    const std::string where = path + ":" + std::to_string(n);
    std::vector<double> v(tok.size());
    bool numeric = true;
    for (std::size_t k = 0; k < tok.size(); ++k) numeric = numeric && parse_real(tok[k], v[k]);
    if (!numeric) {
      if (!header_seen && g.particles.empty()) {
        header_seen = true;  // a header row of column names
        continue;
      }
      throw InputError(where, "row", "'" + line + "'", "expected numbers: x y z radius");
    }
    ParticleSpec p;
    p.tag = g.particles.size() + 1;
    p.density = density;
    if (v.size() == 4) {
      p.position = {v[0], v[1], v[2]};
      p.radius = v[3];
      if (dim == Dimension::Two && v[2] != 0.0)
        throw InputError(where, "z", num(v[2]), "2D samples lie in the plane z = 0");
    } else if (v.size() == 3 && dim == Dimension::Two) {
      p.position = {v[0], v[1], 0.0};
      p.radius = v[2];
    } else {
      throw InputError(where, "columns", std::to_string(v.size()),
                       dim == Dimension::Two ? "expected 3 (x y radius) or 4 (x y z radius)"
                                             : "expected 4 (x y z radius)");
    }
    if (!(p.radius > 0.0)) throw InputError(where, "radius", num(p.radius), "must be > 0 m");
    g.particles.push_back(p);
  }
  if (g.particles.empty()) throw InputError(path, "particles", "0", "the table has no rows");
  return g;
}

GeometryData read_gengeo(const std::string& path, double density, double thickness) {
  std::ifstream in = open(path);
  GeometryData g;
  std::string line;
  std::size_t n = 0;
  auto next = [&](std::vector<std::string>& tok) {
    while (std::getline(in, line)) {
      ++n;
      tok = split(line);
      if (!tok.empty()) return true;
    }
    return false;
  };
  auto where = [&] { return path + ":" + std::to_string(n); };
  std::vector<std::string> tok;
  if (!next(tok) || tok.size() < 2 || tok[0] != "LSMGeometry")
    throw InputError(where(), "header", tok.empty() ? "(empty)" : "'" + tok[0] + "'",
                     "expected 'LSMGeometry 1.2' (a GenGeo geometry file)");
  if (tok[1] != "1.2")
    throw InputError(where(), "version", tok[1], "only LSMGeometry 1.2 is supported");
  auto count = [&](const char* what) {
    if (!next(tok) || tok.size() != 1)
      throw InputError(where(), what, tok.empty() ? "" : tok[0], "expected a count");
    double v = 0.0;
    if (!parse_real(tok[0], v) || v < 0 || v != std::floor(v))
      throw InputError(where(), what, tok[0], "expected a non-negative integer");
    return static_cast<std::size_t>(v);
  };
  bool dim_seen = false;
  while (next(tok)) {
    if (tok[0] == "Dimension") {
      dim_seen = true;
      if (tok.size() < 2 || (tok[1] != "3D" && tok[1] != "2D"))
        throw InputError(where(), "Dimension", tok.size() > 1 ? tok[1] : "", "allowed: 3D, 2D");
      g.dimension = tok[1] == "2D" ? Dimension::Two : Dimension::Three;
      g.thickness = g.dimension == Dimension::Two ? thickness : 1.0;
    } else if (tok[0] == "BeginParticles") {
      if (!next(tok) || tok[0] != "Simple")
        throw InputError(where(), "particle type", tok.empty() ? "" : tok[0],
                         "only 'Simple' particles are supported");
      const std::size_t np = count("particle count");
      for (std::size_t k = 0; k < np; ++k) {
        if (!next(tok) || tok.size() < 5)
          throw InputError(where(), "particle", line, "expected x y z radius id tag");
        double v[5];
        for (int c = 0; c < 5; ++c)
          if (!parse_real(tok[static_cast<std::size_t>(c)], v[c]))
            throw InputError(where(), "particle", "'" + tok[static_cast<std::size_t>(c)] + "'",
                             "expected a number");
        if (!(v[3] > 0.0)) throw InputError(where(), "radius", num(v[3]), "must be > 0");
        ParticleSpec p;
        p.position = {v[0], v[1], g.dimension == Dimension::Two ? 0.0 : v[2]};
        p.radius = v[3];
        p.tag = static_cast<std::uint64_t>(v[4]) + 1;
        p.density = density;
        g.particles.push_back(p);
      }
      if (!next(tok) || tok[0] != "EndParticles")
        throw InputError(where(), "EndParticles", tok.empty() ? "" : tok[0],
                         "the particle count does not match the rows");
    } else if (tok[0] == "BeginConnect") {
      const std::size_t nb = count("bond count");
      for (std::size_t k = 0; k < nb; ++k) {
        double a = 0, b = 0;
        if (!next(tok) || tok.size() < 2 || !parse_real(tok[0], a) || !parse_real(tok[1], b))
          throw InputError(where(), "bond", line, "expected id1 id2 tag");
        g.bonds.emplace_back(static_cast<std::uint64_t>(a) + 1, static_cast<std::uint64_t>(b) + 1);
      }
      if (!next(tok) || tok[0] != "EndConnect")
        throw InputError(where(), "EndConnect", tok.empty() ? "" : tok[0],
                         "the bond count does not match the rows");
    }
  }
  if (!dim_seen) throw InputError(path, "Dimension", "", "the file has no Dimension line");
  if (g.particles.empty()) throw InputError(path, "particles", "0", "the file has no particles");
  return g;
}

}  // namespace breccia
