// The explicit geometry loader: a valid file, a round trip, and every kind of bad input giving an
// error that names the file and line, the key, the value and what is allowed.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>

#include "breccia/core/error.hpp"
#include "breccia/engine/simulation.hpp"
#include "breccia/sample/geometry_file.hpp"
#include "breccia/sample/sample_import.hpp"
#include "breccia/sample/spatial_order.hpp"

using namespace breccia;

namespace {
const char* kValid = R"(# two bonded spheres
breccia-geometry 1
dimension 3
particles 3
# tag x y z radius density
1 0     0 0 0.0005 2650
2 0.001 0 0 0.0005 2650 driven 0.001 0 0
5 0.002 0 0 0.0005 2650 fixed
bonds 2
1 2
2 5
)";

// Expects parse_geometry to throw an InputError whose message contains every fragment.
void expect_error(const std::string& text, std::initializer_list<const char*> fragments) {
  try {
    parse_geometry(text, "sample.geo");
    ADD_FAILURE() << "no error for:\n" << text;
  } catch (const InputError& e) {
    const std::string m = e.what();
    for (const char* f : fragments) EXPECT_NE(m.find(f), std::string::npos) << m << " lacks " << f;
  }
}

std::string with_particles(const std::string& rows, int n,
                           const std::string& head = "dimension 3\n") {
  return "breccia-geometry 1\n" + head + "particles " + std::to_string(n) + "\n" + rows;
}
}  // namespace

TEST(GeometryFile, ParsesParticlesMotionAndBonds) {
  const GeometryData g = parse_geometry(kValid, "sample.geo");
  ASSERT_EQ(g.particles.size(), 3u);
  EXPECT_EQ(g.particles[1].motion, Motion::Driven);
  EXPECT_EQ(g.particles[1].velocity.x, 0.001);
  EXPECT_EQ(g.particles[2].motion, Motion::Fixed);
  EXPECT_EQ(g.particles[2].tag, 5u);
  ASSERT_EQ(g.bonds.size(), 2u);
  EXPECT_EQ(g.bonds[1], (std::pair<std::uint64_t, std::uint64_t>{2, 5}));
  // And it builds a simulation.
  Simulation sim(g.make_store(), EngineConfig{}, make_contact_model<LinearContact>({}, {}));
  for (auto [a, b] : g.bonds) sim.add_bond<ParallelBond>(a, b);
  sim.initialise();
  EXPECT_EQ(sim.intact_bonds(), 2u);
}

TEST(GeometryFile, RoundTripIsExact) {
  GeometryData g = parse_geometry(kValid, "sample.geo");
  g.particles[0].position.y = 0.1 + 0.2;  // not exactly representable in short decimal
  const auto path = std::filesystem::temp_directory_path() / "breccia_roundtrip.geo";
  write_geometry(path.string(), g);
  const GeometryData h = read_geometry(path.string());
  std::filesystem::remove(path);
  ASSERT_EQ(h.particles.size(), g.particles.size());
  for (std::size_t i = 0; i < g.particles.size(); ++i) {
    EXPECT_EQ(h.particles[i].position, g.particles[i].position);
    EXPECT_EQ(h.particles[i].radius, g.particles[i].radius);
    EXPECT_EQ(h.particles[i].motion, g.particles[i].motion);
    EXPECT_EQ(h.particles[i].velocity, g.particles[i].velocity);
  }
  EXPECT_EQ(h.bonds, g.bonds);
}

TEST(GeometryFile, MissingFileNamesThePath) {
  try {
    read_geometry("/nonexistent/dir/x.geo");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/dir/x.geo"), std::string::npos);
  }
}

TEST(GeometryFile, BadInputGivesClearErrors) {
  expect_error("", {"sample.geo", "breccia-geometry 1"});
  expect_error("hello 1\n", {"sample.geo:1", "breccia-geometry 1"});
  expect_error("breccia-geometry 2\n", {"sample.geo:1", "version", "2"});
  expect_error("breccia-geometry 1\ncolour red\n",
               {"sample.geo:2", "colour", "allowed: dimension"});
  expect_error("breccia-geometry 1\ndimension 4\n", {"sample.geo:2", "dimension", "4", "2 or 3"});
  expect_error("breccia-geometry 1\nthickness -1\n", {"sample.geo:2", "thickness", "> 0"});
  expect_error(with_particles("1 0 0 0 -0.001 2650\n", 1),
               {"sample.geo:4", "radius", "-0.001", "> 0 m"});
  expect_error(with_particles("1 0 0 0 0.001 0\n", 1), {"sample.geo:4", "density", "> 0"});
  expect_error(with_particles("1 0 0 zero 0.001 2650\n", 1),
               {"sample.geo:4", "'z'", "'zero'", "finite number"});
  expect_error(with_particles("1 0 0 nan 0.001 2650\n", 1), {"sample.geo:4", "'z'", "finite"});
  expect_error(with_particles("1 0 0 0.001 2650\n", 1), {"sample.geo:4", "5 columns", "tag x y z"});
  expect_error(with_particles("1 0 0 0 0.001 2650 flying\n", 1),
               {"sample.geo:4", "motion", "flying", "free, fixed, driven"});
  expect_error(with_particles("1 0 0 0 0.001 2650\n", 2), {"end of file", "announced 2"});
  expect_error(with_particles("1 0 0 0 0.001 2650\n1 1 0 0 0.001 2650\n", 2),
               {"tag", "1", "unique"});
  expect_error(with_particles("1 0 0 0.5 0.001 2650\n", 1, "dimension 2\n"),
               {"sample.geo:4", "x-y plane"});
  expect_error(with_particles("1 0 0 0 0.001 2650\nbonds 1\n1 9\n", 1),
               {"sample.geo:6", "tag2", "9", "no particle"});
  expect_error(with_particles("1 0 0 0 0.001 2650\nbonds 1\n1 1\n", 1), {"sample.geo:6", "itself"});
  expect_error(with_particles("1 0 0 0 0.001 2650\nbonds 1\n1\n", 1),
               {"sample.geo:6", "tag1 tag2"});
  expect_error("breccia-geometry 1\nbonds 0\n",
               {"sample.geo:2", "particles section must come first"});
  expect_error("breccia-geometry 1\ndimension 3\n", {"particles", "required"});
}

TEST(GeometryFile, DuplicateBondIsRejectedAtInitialise) {
  const GeometryData g = parse_geometry(kValid, "sample.geo");
  Simulation sim(g.make_store(), EngineConfig{}, make_contact_model<LinearContact>({}, {}));
  sim.add_bond<ParallelBond>(1, 2);
  sim.add_bond<ParallelBond>(2, 1);
  EXPECT_THROW(sim.initialise(), InputError);
}

// An editor's UTF-8 byte-order mark in front of a sample file is dropped, as TOML files get it
// dropped by their parser: the same sample reads the same with or without it, in every format.
TEST(GeometryFile, AByteOrderMarkIsDroppedInEveryFormat) {
  const std::filesystem::path dir = std::filesystem::temp_directory_path() / "breccia_bom";
  std::filesystem::create_directories(dir);
  const std::string bom = "\xEF\xBB\xBF";
  const std::string geom =
      "breccia-geometry 1\ndimension 3\nparticles 2\n1 0 0 0 1e-3 2650\n"
      "2 2e-3 0 0 1e-3 2650\n";
  const std::string table = "0 0 0 1e-3\n2e-3 0 0 1e-3\n";
  for (const auto& [name, text] :
       {std::pair{"a.geom", bom + geom}, std::pair{"b.txt", bom + table}})
    std::ofstream(dir / name) << text;
  const GeometryData g = read_geometry((dir / "a.geom").string(), 100);
  ASSERT_EQ(g.particles.size(), 2u);
  EXPECT_EQ(g.particles[1].position[0], 2e-3);
  const GeometryData t =
      read_xyzr_table((dir / "b.txt").string(), Dimension::Three, 2650.0, 0.0, 100);
  ASSERT_EQ(t.particles.size(), 2u);
  EXPECT_EQ(t.particles[0].radius, 1e-3);
  std::filesystem::remove_all(dir);
}

// The run sorts particles along a Morton curve: neighbours in space sit near each other in the
// arrays, tags and bonds are kept, and the order is a permutation of the input.
TEST(GeometryFile, SpatialOrderIsAMortonPermutationThatKeepsTags) {
  GeometryData g;
  // A 4 x 4 x 4 lattice listed in a scrambled order (i -> 37 i mod 64 is a bijection).
  for (int k = 0; k < 64; ++k) {
    const int c = (37 * k) % 64;
    ParticleSpec p;
    p.tag = static_cast<std::uint64_t>(100 + c);
    p.position = {1e-3 * (c % 4), 1e-3 * ((c / 4) % 4), 1e-3 * (c / 16)};
    p.radius = 0.5e-3;
    p.density = 2650;
    g.particles.push_back(p);
    g.particle_lines.push_back(static_cast<std::size_t>(10 + k));
  }
  g.bonds = {{100, 101}};
  const std::vector<ParticleSpec> before = g.particles;
  sort_spatially(g);
  ASSERT_EQ(g.particles.size(), 64u);
  std::vector<std::uint64_t> tags;
  for (std::size_t k = 0; k < 64; ++k) {
    tags.push_back(g.particles[k].tag);
    // Each line number still belongs to its particle.
    const std::size_t was = g.particle_lines[k] - 10;
    EXPECT_EQ(before[was].tag, g.particles[k].tag);
  }
  std::sort(tags.begin(), tags.end());
  for (std::size_t k = 0; k < 64; ++k) EXPECT_EQ(tags[k], 100 + k);
  // Z-order of a 4^3 lattice: x varies fastest, then y, then z within each 2^3 octant, so the
  // first eight are the octant at the origin, in the order (0,0,0), (1,0,0), (0,1,0), (1,1,0)...
  const int first_octant[8] = {0, 1, 4, 5, 16, 17, 20, 21};
  for (int k = 0; k < 8; ++k) EXPECT_EQ(g.particles[k].tag, 100u + first_octant[k]) << k;
  // Keys increase along the sorted order.
  const Vec3 lo{0, 0, 0}, hi{3e-3, 3e-3, 3e-3};
  for (std::size_t k = 1; k < 64; ++k)
    EXPECT_LT(morton_key(g.particles[k - 1].position, lo, hi),
              morton_key(g.particles[k].position, lo, hi));
  EXPECT_EQ(g.bonds.size(), 1u);
}
