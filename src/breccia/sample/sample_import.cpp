#include "breccia/sample/sample_import.hpp"

#include <charconv>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "breccia/core/error.hpp"
#include "breccia/core/format.hpp"
#include "breccia/core/text_file.hpp"
#include "breccia/sample/geometry_checks.hpp"

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

// The whole token is a number (nan and inf included: they are numbers, not words).
bool parse_number(const std::string& t, double& v) {
  const auto r = std::from_chars(t.data(), t.data() + t.size(), v);
  return r.ec == std::errc() && r.ptr == t.data() + t.size();
}
bool parse_real(const std::string& t, double& v) {
  return parse_number(t, v) && std::isfinite(v);
}

// A GenGeo id: a whole number in [0, 2^53) written as a real.
bool parse_id(const std::string& t, std::uint64_t& id) {
  double v = 0.0;
  if (!parse_real(t, v) || v < 0.0 || v != std::floor(v) || v >= 9007199254740992.0) return false;
  id = static_cast<std::uint64_t>(v);
  return true;
}

std::istringstream open(const std::string& path) {
  return std::istringstream(read_text_file(path, "the sample file"));
}

}  // namespace

GeometryData read_xyzr_table(const std::string& path, Dimension dim, double density,
                             double thickness, std::uint64_t max_particles) {
  std::istringstream in = open(path);
  return parse_xyzr_table(in, path, dim, density, thickness, max_particles);
}

GeometryData parse_xyzr_table(std::istream& in, const std::string& path, Dimension dim,
                              double density, double thickness, std::uint64_t max_particles) {
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
    std::size_t numbers = 0, finite = 0;
    for (std::size_t k = 0; k < tok.size(); ++k)
      if (parse_number(tok[k], v[k])) {
        ++numbers;
        finite += std::isfinite(v[k]) ? 1 : 0;
      }
    if (numbers == 0 && !header_seen && g.particles.empty()) {
      header_seen = true;  // a header row of column names (words only)
      continue;
    }
    if (numbers != tok.size())
      throw InputError(where, "row", "'" + line + "'", "expected numbers: x y z radius");
    if (finite != tok.size())
      throw InputError(where, "row", "'" + line + "'", "expected finite numbers (no nan or inf)");
    if (g.particles.size() >= max_particles)
      throw InputError(where, "particles", "> " + std::to_string(max_particles),
                       "the table holds more particles than sample.max_particles");
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
    g.particle_lines.push_back(n);
  }
  if (g.particles.empty()) throw InputError(path, "particles", "0", "the table has no rows");
  check_geometry(g, path, max_particles);
  return g;
}

GeometryData read_gengeo(const std::string& path, double density, double thickness,
                         std::uint64_t max_particles) {
  std::istringstream in = open(path);
  return parse_gengeo(in, path, density, thickness, max_particles);
}

namespace {

// The lines of a GenGeo file, blank ones skipped, with the number of the last one read.
class GengeoReader {
 public:
  GengeoReader(std::istream& in, const std::string& path) : in_(in), path_(path) {}
  // The next non-blank line's tokens into `tok`; false at the end of the file.
  bool next(std::vector<std::string>& tok) {
    while (std::getline(in_, line_)) {
      ++n_;
      tok = split(line_);
      if (!tok.empty()) return true;
    }
    return false;
  }
  std::string where() const { return path_ + ":" + std::to_string(n_); }
  const std::string& line() const noexcept { return line_; }
  std::size_t number() const noexcept { return n_; }
  // A line holding one count, at most `limit`.
  std::size_t count(const char* what, std::uint64_t limit) {
    std::vector<std::string> tok;
    if (!next(tok) || tok.size() != 1)
      throw InputError(where(), what, tok.empty() ? "" : tok[0], "expected a count");
    std::uint64_t v = 0;
    if (!parse_id(tok[0], v))
      throw InputError(where(), what, tok[0], "expected a non-negative integer");
    check_announced_count(v, limit, where(), what);
    return static_cast<std::size_t>(v);
  }
  // The line that closes a section.
  void expect_end(const char* end, const char* allowed) {
    std::vector<std::string> tok;
    if (!next(tok) || tok[0] != end)
      throw InputError(where(), end, tok.empty() ? "" : tok[0], allowed);
  }

 private:
  std::istream& in_;
  std::string path_, line_;
  std::size_t n_ = 0;
};

// BeginParticles ... EndParticles: "x y z radius id tag" rows (ids from 0; tags are id + 1).
void read_gengeo_particles(GengeoReader& rd, GeometryData& g, double density,
                           std::uint64_t max_particles) {
  std::vector<std::string> tok;
  if (!rd.next(tok) || tok[0] != "Simple")
    throw InputError(rd.where(), "particle type", tok.empty() ? "" : tok[0],
                     "only 'Simple' particles are supported");
  const std::size_t np = rd.count("particle count", max_particles);
  for (std::size_t k = 0; k < np; ++k) {
    if (!rd.next(tok) || tok.size() < 5)
      throw InputError(rd.where(), "particle", rd.line(), "expected x y z radius id tag");
    double v[4];
    for (int c = 0; c < 4; ++c)
      if (!parse_real(tok[static_cast<std::size_t>(c)], v[c]))
        throw InputError(rd.where(), "particle", "'" + tok[static_cast<std::size_t>(c)] + "'",
                         "expected a finite number");
    if (!(v[3] > 0.0)) throw InputError(rd.where(), "radius", num(v[3]), "must be > 0");
    std::uint64_t id = 0;
    if (!parse_id(tok[4], id))
      throw InputError(rd.where(), "id", "'" + tok[4] + "'",
                       "expected a non-negative whole number below 2^53");
    ParticleSpec p;
    p.position = {v[0], v[1], g.dimension == Dimension::Two ? 0.0 : v[2]};
    p.radius = v[3];
    p.tag = id + 1;
    p.density = density;
    g.particles.push_back(p);
    g.particle_lines.push_back(rd.number());
  }
  rd.expect_end("EndParticles", "the particle count does not match the rows");
}

// BeginConnect ... EndConnect: "id1 id2 tag" rows.
void read_gengeo_bonds(GengeoReader& rd, GeometryData& g, std::uint64_t max_particles) {
  std::vector<std::string> tok;
  const std::size_t nb = rd.count("bond count", kMaxBondsPerParticle * max_particles);
  for (std::size_t k = 0; k < nb; ++k) {
    std::uint64_t a = 0, b = 0;
    if (!rd.next(tok) || tok.size() < 2)
      throw InputError(rd.where(), "bond", "'" + rd.line() + "'", "expected id1 id2 tag");
    if (!parse_id(tok[0], a) || !parse_id(tok[1], b))
      throw InputError(rd.where(), "bond", "'" + rd.line() + "'",
                       "particle ids are non-negative whole numbers below 2^53");
    g.bonds.emplace_back(a + 1, b + 1);
    g.bond_lines.push_back(rd.number());
  }
  rd.expect_end("EndConnect", "the bond count does not match the rows");
}

}  // namespace

GeometryData parse_gengeo(std::istream& in, const std::string& path, double density,
                          double thickness, std::uint64_t max_particles) {
  GeometryData g;
  GengeoReader rd(in, path);
  std::vector<std::string> tok;
  if (!rd.next(tok) || tok.size() < 2 || tok[0] != "LSMGeometry")
    throw InputError(rd.where(), "header", tok.empty() ? "(empty)" : "'" + tok[0] + "'",
                     "expected 'LSMGeometry 1.2' (a GenGeo geometry file)");
  if (tok[1] != "1.2")
    throw InputError(rd.where(), "version", tok[1], "only LSMGeometry 1.2 is supported");
  bool dim_seen = false;
  while (rd.next(tok)) {
    if (tok[0] == "Dimension") {
      dim_seen = true;
      if (tok.size() < 2 || (tok[1] != "3D" && tok[1] != "2D"))
        throw InputError(rd.where(), "Dimension", tok.size() > 1 ? tok[1] : "", "allowed: 3D, 2D");
      g.dimension = tok[1] == "2D" ? Dimension::Two : Dimension::Three;
      g.thickness = g.dimension == Dimension::Two ? thickness : 1.0;
    } else if (tok[0] == "BeginParticles") {
      read_gengeo_particles(rd, g, density, max_particles);
    } else if (tok[0] == "BeginConnect") {
      read_gengeo_bonds(rd, g, max_particles);
    }
  }
  if (!dim_seen) throw InputError(path, "Dimension", "", "the file has no Dimension line");
  if (g.particles.empty()) throw InputError(path, "particles", "0", "the file has no particles");
  check_geometry(g, path, max_particles);
  return g;
}

}  // namespace breccia
