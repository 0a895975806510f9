#include "breccia/sample/geometry_file.hpp"

#include <fmt/format.h>
#include <fmt/os.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string_view>

#include "breccia/core/error.hpp"
#include "breccia/core/text_file.hpp"
#include "breccia/sample/geometry_checks.hpp"

namespace breccia {

namespace {

struct Line {
  std::size_t number = 0;
  std::vector<std::string> tokens;
};

// Reads the text one line at a time: a million-grain file holds tens of millions of numbers,
// and keeping each as a token string would take several times the file's size.
class Reader {
 public:
  Reader(const std::string& text, std::string source) : text_(text), source_(std::move(source)) {
    advance();
  }
  bool done() const { return !has_line_; }
  Line next() {
    Line l = std::move(line_);
    advance();
    return l;
  }
  std::string where(const Line& l) const { return source_ + ":" + std::to_string(l.number); }
  std::string where_end() const { return source_ + ": end of file"; }

  double real(const Line& l, std::size_t k, const char* key) const {
    const std::string& t = l.tokens[k];
    double v = 0.0;
    const auto r = std::from_chars(t.data(), t.data() + t.size(), v);
    if (r.ec != std::errc() || r.ptr != t.data() + t.size() || !std::isfinite(v))
      throw InputError(where(l), key, "'" + t + "'", "expected a finite number");
    return v;
  }
  std::uint64_t integer(const Line& l, std::size_t k, const char* key) const {
    const std::string& t = l.tokens[k];
    std::uint64_t v = 0;
    const auto r = std::from_chars(t.data(), t.data() + t.size(), v);
    if (r.ec != std::errc() || r.ptr != t.data() + t.size())
      throw InputError(where(l), key, "'" + t + "'", "expected a non-negative integer");
    return v;
  }

 private:
  // Moves to the next line with a token (comments after '#' and blank lines are skipped).
  void advance() {
    has_line_ = false;
    line_ = Line{};
    while (pos_ < text_.size()) {
      std::size_t end = text_.find('\n', pos_);
      if (end == std::string::npos) end = text_.size();
      std::string_view raw(text_.data() + pos_, end - pos_);
      pos_ = end + 1;
      ++number_;
      if (const auto hash = raw.find('#'); hash != std::string_view::npos)
        raw = raw.substr(0, hash);
      constexpr std::string_view kSpace = " \t\r\v\f";
      for (std::size_t b = raw.find_first_not_of(kSpace); b != std::string_view::npos;) {
        const std::size_t e = std::min(raw.find_first_of(kSpace, b), raw.size());
        line_.tokens.emplace_back(raw.substr(b, e - b));
        b = raw.find_first_not_of(kSpace, e);
      }
      if (!line_.tokens.empty()) {
        line_.number = number_;
        has_line_ = true;
        return;
      }
    }
  }

  const std::string& text_;
  std::string source_;
  std::size_t pos_ = 0, number_ = 0;
  Line line_;
  bool has_line_ = false;
};

}  // namespace

namespace {

void read_header(Reader& rd) {
  if (rd.done())
    throw InputError(rd.where_end(), "header", "(empty)",
                     "the file must start with 'breccia-geometry 1'");
  const Line& h = rd.next();
  if (h.tokens.size() != 2 || h.tokens[0] != "breccia-geometry")
    throw InputError(rd.where(h), "header", "'" + h.tokens[0] + "'",
                     "the file must start with 'breccia-geometry 1'");
  if (h.tokens[1] != "1")
    throw InputError(rd.where(h), "version", h.tokens[1], "this Breccia reads version 1");
}

Motion motion_of(const Reader& rd, const Line& p) {
  const std::string& m = p.tokens[6];
  if (m == "free") return Motion::Free;
  if (m == "fixed") return Motion::Fixed;
  if (m == "driven") return Motion::Driven;
  throw InputError(rd.where(p), "motion", "'" + m + "'", "allowed: free, fixed, driven");
}

// One row of the particles section: tag x y z radius density [motion [vx vy vz [wx wy wz]]].
ParticleSpec read_particle(const Reader& rd, const Line& p, Dimension dimension) {
  const std::size_t nt = p.tokens.size();
  if (nt != 6 && nt != 7 && nt != 10 && nt != 13)
    throw InputError(rd.where(p), "particle row", std::to_string(nt) + " columns",
                     "expected: tag x y z radius density [motion [vx vy vz [wx wy wz]]]");
  ParticleSpec s;
  s.tag = rd.integer(p, 0, "tag");
  s.position = {rd.real(p, 1, "x"), rd.real(p, 2, "y"), rd.real(p, 3, "z")};
  s.radius = rd.real(p, 4, "radius");
  if (!(s.radius > 0.0)) throw InputError(rd.where(p), "radius", p.tokens[4], "must be > 0 m");
  s.density = rd.real(p, 5, "density");
  if (!(s.density > 0.0))
    throw InputError(rd.where(p), "density", p.tokens[5], "must be > 0 kg/m^3");
  if (nt >= 7) s.motion = motion_of(rd, p);
  if (nt >= 10) s.velocity = {rd.real(p, 7, "vx"), rd.real(p, 8, "vy"), rd.real(p, 9, "vz")};
  if (nt >= 13)
    s.angular_velocity = {rd.real(p, 10, "wx"), rd.real(p, 11, "wy"), rd.real(p, 12, "wz")};
  if (dimension == Dimension::Two && (s.position.z != 0.0 || s.velocity.z != 0.0 ||
                                      s.angular_velocity.x != 0.0 || s.angular_velocity.y != 0.0))
    throw InputError(rd.where(p), "z / vz / wx / wy", "non-zero",
                     "2D particles lie in the x-y plane: these must be 0");
  return s;
}

// The `count` rows a section header announced; `what` names the section in errors.
template <class ReadRow>
void read_rows(Reader& rd, std::uint64_t count, const char* what, ReadRow&& read_row) {
  for (std::uint64_t k = 0; k < count; ++k) {
    if (rd.done())
      throw InputError(rd.where_end(), what, std::to_string(k) + " rows",
                       "the header announced " + std::to_string(count));
    read_row(rd.next());
  }
}

// One keyed line (and the rows of a section) of the body.
void read_body_line(Reader& rd, const Line& l, GeometryData& g, std::uint64_t max_particles,
                    bool& have_particles, bool& have_bonds) {
  const std::string& key = l.tokens[0];
  auto need_args = [&](std::size_t n, const char* allowed) {
    if (l.tokens.size() != n + 1)
      throw InputError(rd.where(l), key, std::to_string(l.tokens.size() - 1) + " values", allowed);
  };
  if (key == "dimension") {
    need_args(1, "expects one value: 2 or 3");
    const auto d = rd.integer(l, 1, "dimension");
    if (d != 2 && d != 3)
      throw InputError(rd.where(l), "dimension", l.tokens[1], "allowed: 2 or 3");
    g.dimension = d == 2 ? Dimension::Two : Dimension::Three;
  } else if (key == "thickness") {
    need_args(1, "expects one value in m");
    g.thickness = rd.real(l, 1, "thickness");
    if (!(g.thickness > 0.0))
      throw InputError(rd.where(l), "thickness", l.tokens[1], "must be > 0 m");
  } else if (key == "particles") {
    if (have_particles) throw InputError(rd.where(l), key, "", "appears twice; allowed once");
    need_args(1, "expects the particle count");
    const auto count = rd.integer(l, 1, "particles");
    check_announced_count(count, max_particles, rd.where(l), "particles");
    have_particles = true;
    read_rows(rd, count, "particles", [&](const Line& p) {
      g.particles.push_back(read_particle(rd, p, g.dimension));
      g.particle_lines.push_back(p.number);
    });
  } else if (key == "bonds") {
    if (have_bonds) throw InputError(rd.where(l), key, "", "appears twice; allowed once");
    if (!have_particles)
      throw InputError(rd.where(l), key, "", "the particles section must come first");
    need_args(1, "expects the bond count");
    const auto count = rd.integer(l, 1, "bonds");
    check_announced_count(count, kMaxBondsPerParticle * max_particles, rd.where(l), "bonds");
    have_bonds = true;
    read_rows(rd, count, "bonds", [&](const Line& b) {
      if (b.tokens.size() != 2)
        throw InputError(rd.where(b), "bond row", std::to_string(b.tokens.size()) + " columns",
                         "expected: tag1 tag2");
      g.bonds.emplace_back(rd.integer(b, 0, "tag1"), rd.integer(b, 1, "tag2"));
      g.bond_lines.push_back(b.number);
    });
  } else {
    throw InputError(rd.where(l), "'" + key + "'", "",
                     "unknown key; allowed: dimension, thickness, particles, bonds");
  }
}

}  // namespace

GeometryData parse_geometry(const std::string& text, const std::string& source,
                            std::uint64_t max_particles) {
  Reader rd(text, source);
  read_header(rd);
  GeometryData g;
  bool have_particles = false, have_bonds = false;
  while (!rd.done()) read_body_line(rd, rd.next(), g, max_particles, have_particles, have_bonds);
  if (!have_particles)
    throw InputError(source, "particles", "(missing)", "a 'particles N' section is required");
  check_geometry(g, source, max_particles);
  return g;
}

GeometryData read_geometry(const std::string& path, std::uint64_t max_particles) {
  return parse_geometry(read_text_file(path, "the geometry file"), path, max_particles);
}

GeometryData GeometryData::of_store(const ParticleStore& ps) {
  GeometryData g;
  g.dimension = ps.dimension();
  g.thickness = ps.thickness();
  g.particles.reserve(ps.size());
  for (std::size_t i = 0; i < ps.size(); ++i)
    g.particles.push_back({.tag = ps.tag[i],
                           .position = ps.pos_rad[i].x,
                           .radius = ps.pos_rad[i].r,
                           .density = ps.density[i],
                           .velocity = ps.vel[i],
                           .angular_velocity = ps.angvel[i],
                           .motion = ps.motion[i]});
  return g;
}

ParticleStore GeometryData::make_store(PlanarBody body) const {
  ParticleStore s(dimension, thickness, body);
  s.reserve(particles.size());
  for (const ParticleSpec& p : particles) s.add(p);
  return s;
}

void write_geometry(const std::string& path, const GeometryData& g) {
  auto out = fmt::output_file(path);
  out.print("breccia-geometry 1\ndimension {}\n", g.dimension == Dimension::Two ? 2 : 3);
  if (g.dimension == Dimension::Two) out.print("thickness {:.17g}\n", g.thickness);
  out.print("particles {}\n# tag x y z radius density motion vx vy vz wx wy wz\n",
            g.particles.size());
  for (const ParticleSpec& p : g.particles) {
    const char* m =
        p.motion == Motion::Free ? "free" : (p.motion == Motion::Fixed ? "fixed" : "driven");
    out.print(
        "{} {:.17g} {:.17g} {:.17g} {:.17g} {:.17g} {} {:.17g} {:.17g} {:.17g} {:.17g} {:.17g} "
        "{:.17g}\n",
        p.tag, p.position.x, p.position.y, p.position.z, p.radius, p.density, m, p.velocity.x,
        p.velocity.y, p.velocity.z, p.angular_velocity.x, p.angular_velocity.y,
        p.angular_velocity.z);
  }
  out.print("bonds {}\n", g.bonds.size());
  for (const auto& [a, b] : g.bonds) out.print("{} {}\n", a, b);
}

}  // namespace breccia
