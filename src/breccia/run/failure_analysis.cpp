#include "breccia/run/failure_analysis.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <fstream>
#include <numbers>
#include <sstream>

#include "breccia/analysis/correlation_dimension.hpp"
#include "breccia/analysis/crack_series.hpp"
#include "breccia/analysis/fragments.hpp"
#include "breccia/analysis/gutenberg_richter.hpp"
#include "breccia/analysis/moment_tensor.hpp"
#include "breccia/analysis/stages.hpp"
#include "breccia/core/error.hpp"
#include "breccia/core/interrupt.hpp"
#include "breccia/core/text_file.hpp"
#include "breccia/observe/recorders.hpp"

namespace breccia {

namespace fs = std::filesystem;
using json = nlohmann::json;
using analysis::kNaN;

namespace {

// Stops the analysis at a signal, where its inputs allow (FailureInputs::stoppable).
void poll(const FailureInputs& in, const char* stage) {
  if (in.stoppable) throw_if_interrupted(stage);
}

// Writes a small file atomically (temporary name, then rename); the tables with a row per crack,
// event or fragment stream through an AtomicFileWriter instead, since a million-grain run's
// catalogue as one string (and its copies as the string grows) would cost hundreds of megabytes.
void put(const fs::path& p, const std::string& text) {
  write_file_atomically(p, text);
}

std::string g(double v) {
  return std::isfinite(v) ? fmt::format("{:.9g}", v) : "nan";
}

json jnum(double v) {
  return std::isfinite(v) ? json(v) : json(nullptr);
}

// The numeric columns of history.csv, by name.
struct Table {
  std::vector<std::string> columns;
  std::vector<std::vector<double>> rows;
  std::size_t col(const std::string& name) const {
    const auto it = std::find(columns.begin(), columns.end(), name);
    if (it == columns.end()) throw InputError("history.csv", name, "", "column missing");
    return static_cast<std::size_t>(it - columns.begin());
  }
  double at(std::size_t row, const std::string& name) const { return rows[row][col(name)]; }
  bool has(const std::string& name) const {
    return std::find(columns.begin(), columns.end(), name) != columns.end();
  }
};

// The work done on the sample up to a row: walls and driven grains, and the loads applied to
// grains (membranes), which a run recorded before that column existed did not write.
double work_in(const Table& hist, std::size_t row) {
  return hist.at(row, "boundary_work_j") +
         (hist.has("external_load_work_j") ? hist.at(row, "external_load_work_j") : 0.0);
}

Table read_table(const fs::path& p) {
  Table t;
  std::ifstream in(p);
  std::string line;
  if (!std::getline(in, line)) return t;
  std::stringstream header(line);
  for (std::string c; std::getline(header, c, ',');) t.columns.push_back(c);
  while (std::getline(in, line)) {
    std::vector<double> v;
    std::stringstream ss(line);
    for (std::string c; std::getline(ss, c, ',');) v.push_back(std::strtod(c.c_str(), nullptr));
    if (v.size() == t.columns.size()) t.rows.push_back(std::move(v));
  }
  return t;
}

// An evenly strided subset of at most `cap` points (deterministic), for D2 of large windows.
std::vector<Vec3> thin(const std::vector<Vec3>& p, std::size_t cap, bool& thinned) {
  thinned = p.size() > cap;
  if (!thinned) return p;
  std::vector<Vec3> out;
  for (std::size_t k = 0; k < cap; ++k) out.push_back(p[k * p.size() / cap]);
  return out;
}

constexpr std::size_t kD2Cap = 3000;

// The run's cracks as the analyses read them: midpoint, strain, mode and released energy (the
// crack context of the AE monitor may lag the crack list by the cracks of the last step).
struct CrackPoints {
  std::size_t count = 0;
  std::vector<Vec3> position;
  std::vector<double> strain, energy;
  std::vector<char> shear;
};

CrackPoints crack_points(const FailureInputs& in) {
  auto cracks = in.sim.cracks().reader();
  const auto& ctx = in.ae.crack_context();
  CrackPoints c;
  c.count = std::min(cracks.size(), ctx.size());
  c.position.reserve(c.count);
  c.strain.reserve(c.count);
  c.energy.reserve(c.count);
  c.shear.reserve(c.count);
  for (std::size_t k = 0; k < c.count; ++k) {
    c.position.push_back(cracks[k].position);
    c.strain.push_back(ctx[k].axial_strain);
    c.energy.push_back(cracks[k].energy.total());
    c.shear.push_back(cracks[k].mode == CrackMode::Shear ? 1 : 0);
  }
  return c;
}

// The AE events with their magnitudes and source types, numbered in order of their first crack.
struct EventCatalogue {
  std::vector<std::size_t> order;   // event indices by first crack
  std::vector<std::size_t> number;  // event index -> its number
  std::vector<double> magnitude, strain;
  std::vector<analysis::SourceType> source;
  std::vector<double> magnitude_by_strain, strain_sorted;  // events by strain
  std::size_t largest = 0, zero_moment = 0;
  double energy = 0.0, fracture_energy = 0.0, kinetic_energy = 0.0;
};

EventCatalogue catalogue_events(const FailureInputs& in) {
  const std::vector<AeEvent>& ev = in.ae.events();
  const bool planar = in.sim.particles().planar();
  EventCatalogue c;
  c.order.resize(ev.size());
  for (std::size_t k = 0; k < ev.size(); ++k) c.order[k] = k;
  std::sort(c.order.begin(), c.order.end(),
            [&](std::size_t a, std::size_t b) { return ev[a].first_crack < ev[b].first_crack; });
  c.number.resize(ev.size());
  for (std::size_t k = 0; k < c.order.size(); ++k) c.number[c.order[k]] = k;
  c.magnitude.resize(ev.size());
  c.strain.resize(ev.size());
  c.source.resize(ev.size());
  for (std::size_t k = 0; k < ev.size(); ++k) {
    const AeEvent& e = ev[k];
    analysis::Tensor3 m{};
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j)
        m[static_cast<std::size_t>(i)][static_cast<std::size_t>(j)] =
            e.moment[static_cast<std::size_t>(3 * i + j)];
    c.source[k] = analysis::source_type(m, planar);
    if (c.source[k].zero) ++c.zero_moment;
    c.magnitude[k] = in.spec.ae_moment_tensors
                         ? analysis::moment_magnitude(e.m0, in.spec.ae_magnitude_constant)
                         : analysis::energy_magnitude(e.energy);
    c.strain[k] = e.strain_first;
    c.largest = std::max<std::size_t>(c.largest, e.cracks);
    c.energy += e.energy;
    c.fracture_energy += e.fracture_energy;
    c.kinetic_energy += e.ke_gain;
  }
  std::vector<std::size_t> by_strain = c.order;
  std::stable_sort(by_strain.begin(), by_strain.end(),
                   [&](std::size_t a, std::size_t b) { return c.strain[a] < c.strain[b]; });
  for (std::size_t k : by_strain) {
    c.magnitude_by_strain.push_back(c.magnitude[k]);
    c.strain_sorted.push_back(c.strain[k]);
  }
  return c;
}

// events.csv: one row per event, with its moment tensor and source type (§4).
void write_events_csv(const fs::path& folder, const FailureInputs& in, const EventCatalogue& cat,
                      const analysis::Stages& stages) {
  const std::vector<AeEvent>& ev = in.ae.events();
  AtomicFileWriter file(folder / "events.csv");
  std::ostream& out = file.stream();
  out << "event_id,first_crack,t_first_s,t_last_s,axial_strain_first,axial_strain_last,"
         "axial_strain_at_max_moment,x_m,y_m,z_m,cracks,tensile,shear,dominant_mode,stage,"
         "energy_j,fracture_energy_j,ke_energy_j,ke_magnitude,m0_nm,mw,radiated_energy_j,"
         "m_xx,m_yy,m_zz,m_xy,m_xz,m_yz,eigen_1,eigen_2,eigen_3,iso_percent,clvd_percent,"
         "dc_percent,hudson_k,hudson_t,hudson_u,hudson_v,r_ratio,source_type,antisymmetry,"
         "m0_first_nm,evaluations,source_particles,monitored_particles\n";
  for (std::size_t n = 0; n < cat.order.size(); ++n) {
    const std::size_t k = cat.order[n];
    const AeEvent& e = ev[k];
    const analysis::SourceType& q = cat.source[k];
    const Vec3 c = e.centroid();
    const double mw = analysis::moment_magnitude(e.m0, in.spec.ae_magnitude_constant);
    const auto sym = [&](int i, int j) {
      return 0.5 * (e.moment[static_cast<std::size_t>(3 * i + j)] +
                    e.moment[static_cast<std::size_t>(3 * j + i)]);
    };
    const char* type = q.zero              ? "none"
                       : q.r_ratio > 30.0  ? "tensile"
                       : q.r_ratio < -30.0 ? "implosive"
                                           : "shear";
    out << fmt::format(
        "{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},"
        "{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{}\n",
        n, e.first_crack, g(e.t_first), g(e.t_last), g(e.strain_first), g(e.strain_last),
        e.evaluations ? g(e.strain_star) : "nan", g(c.x), g(c.y), g(c.z), e.cracks, e.tensile,
        e.shear, e.tensile >= e.shear ? "tensile" : "shear", stages.stage_of(e.strain_first),
        g(e.energy), g(e.fracture_energy), g(e.ke_gain), g(analysis::energy_magnitude(e.ke_gain)),
        g(e.m0), g(mw), g(std::isfinite(mw) ? analysis::radiated_energy(mw) : kNaN), g(sym(0, 0)),
        g(sym(1, 1)), g(sym(2, 2)), g(sym(0, 1)), g(sym(0, 2)), g(sym(1, 2)), g(q.eigenvalues[0]),
        g(q.eigenvalues[1]), g(q.eigenvalues[2]), g(q.iso_percent), g(q.clvd_percent),
        g(q.dc_percent), g(q.k), g(q.T), g(q.u), g(q.v), g(q.r_ratio), type, g(q.antisymmetry),
        e.m0_first >= 0.0 ? g(e.m0_first) : "nan", e.evaluations, e.source_particles,
        e.monitored_particles);
  }
  file.commit();
}

// cracks.csv rewritten with the derived fields (§3.1): strain, stress, angle to the axis,
// fracture energy, stage and event.
void write_crack_catalogue(const fs::path& folder, const FailureInputs& in,
                           const EventCatalogue& cat, const analysis::Stages& stages,
                           std::size_t nc) {
  auto cracks = in.sim.cracks().reader();
  const auto& ctx = in.ae.crack_context();
  const std::vector<std::size_t> crack_event = in.ae.crack_events();
  const int axis = in.sim.particles().planar() ? 1 : 2;
  AtomicFileWriter file(folder / "cracks.csv");
  std::ostream& out = file.stream();
  for (const std::string& c : crack_columns()) out << c << ',';
  out << "crack_id,axial_strain,deviatoric_stress_pa,theta_axial_deg,fracture_energy_j,stage,"
         "event_id\n";
  for (std::size_t k = 0; k < nc; ++k) {
    const CrackRecord& c = cracks[k];
    const double theta =
        std::acos(std::min(1.0, std::abs(c.normal[axis]))) * 180.0 / std::numbers::pi;
    const std::size_t e = crack_event[k];
    out << crack_row(c)
        << fmt::format(",{},{},{},{},{},{},{}\n", k, g(ctx[k].axial_strain), g(ctx[k].deviatoric),
                       g(theta), g(ctx[k].fracture_energy), stages.stage_of(ctx[k].axial_strain),
                       e < cat.number.size() ? static_cast<long long>(cat.number[e]) : -1LL);
  }
  file.commit();
}

// Frequency-magnitude statistics (§5): completeness, the whole run's b-value and its moving
// windows (written to b_value_windows.csv).
struct MagnitudeStats {
  analysis::Completeness completeness;
  analysis::BValue b_all;
  std::vector<analysis::BValueWindow> windows;
};

MagnitudeStats frequency_magnitude(const fs::path& folder, const FailureInputs& in,
                                   const EventCatalogue& cat) {
  const auto min_events = static_cast<std::size_t>(in.spec.ae_min_events);
  MagnitudeStats m;
  m.completeness = analysis::completeness_max_curvature(cat.magnitude, 0.1, 0.2, min_events);
  m.b_all = analysis::b_value(cat.magnitude, m.completeness.magnitude, 0.0, min_events);
  m.windows = analysis::b_value_windows(
      cat.magnitude_by_strain, cat.strain_sorted, m.completeness.magnitude,
      static_cast<std::size_t>(in.spec.ae_window_events),
      static_cast<std::size_t>(in.spec.ae_window_step), min_events);
  std::string t = "axial_strain,b_value,sigma,a_value,events,flag\n";
  for (const auto& w : m.windows)
    t += fmt::format("{},{},{},{},{},{}\n", g(w.strain), g(w.value.b), g(w.value.sigma),
                     g(w.value.a), w.value.events, w.value.flag);
  put(folder / "b_value_windows.csv", t);
  return m;
}

// Correlation dimension of the crack midpoints (§6): the whole run and its moving windows
// (written to d2_windows.csv).
struct D2Stats {
  analysis::D2Settings settings;
  analysis::CorrelationDimension all;
  bool all_thinned = false;
  std::vector<double> window_values;  // the valid windows' D2
};

D2Stats correlation_dimensions(const fs::path& folder, const FailureInputs& in,
                               const CrackPoints& cp) {
  D2Stats d;
  d.settings.r_hi = 0.25 * in.sample_length_min;
  d.settings.dimension = in.sim.particles().planar() ? 2 : 3;
  d.settings.min_points = static_cast<std::size_t>(in.spec.ae_min_events);
  d.all = analysis::correlation_dimension(thin(cp.position, kD2Cap, d.all_thinned), d.settings);
  std::string t = "axial_strain,d2,standard_error,r2,r_min_m,r_max_m,points,flags\n";
  const auto w = static_cast<std::size_t>(in.spec.ae_window_events);
  const auto step = static_cast<std::size_t>(in.spec.ae_window_step);
  for (std::size_t end = w; end <= cp.count; end += step) {
    poll(in, "computing D2 windows");
    const std::vector<Vec3> p(cp.position.begin() + static_cast<std::ptrdiff_t>(end - w),
                              cp.position.begin() + static_cast<std::ptrdiff_t>(end));
    const auto dw = analysis::correlation_dimension(p, d.settings);
    std::string flags;
    for (const auto& f : dw.flags) flags += (flags.empty() ? "" : ";") + f;
    t += fmt::format("{},{},{},{},{},{},{},{}\n", g(cp.strain[end - 1]), g(dw.d2),
                     g(dw.standard_error), g(dw.r2), g(dw.r_min), g(dw.r_max), dw.points, flags);
    if (dw.valid()) d.window_values.push_back(dw.d2);
  }
  put(folder / "d2_windows.csv", t);
  return d;
}

// The b-value of the events above M_c in the trailing window that ends at strain e1, extended
// back to min_events events; `from` is the strain where its events begin.
analysis::BValue trailing_b_value(const EventCatalogue& cat, double mc, double e1, double window,
                                  std::size_t min_events, double& from) {
  std::vector<std::size_t> idx;
  for (std::size_t k = 0; k < cat.magnitude_by_strain.size(); ++k)
    if (cat.strain_sorted[k] <= e1 && cat.magnitude_by_strain[k] >= mc) idx.push_back(k);
  std::size_t first = idx.size();
  while (first > 0 && cat.strain_sorted[idx[first - 1]] > e1 - window) --first;
  if (idx.size() - first < min_events && idx.size() >= min_events) first = idx.size() - min_events;
  std::vector<double> m_in;
  for (std::size_t k = first; k < idx.size(); ++k) m_in.push_back(cat.magnitude_by_strain[idx[k]]);
  from = e1 - window;
  if (first < idx.size()) from = std::min(from, cat.strain_sorted[idx[first]]);
  return analysis::b_value(m_in, mc, 0.0, min_events);
}

// Porosity from the volumetric strain of the row nearest the strain e1 (§7).
double porosity_at(const FailureInputs& in, double e1) {
  const auto& s = in.series;
  if (s.axial_strain.empty()) return kNaN;
  const auto it = std::lower_bound(s.axial_strain.begin(), s.axial_strain.end(), e1);
  const std::size_t r = std::min<std::size_t>(static_cast<std::size_t>(it - s.axial_strain.begin()),
                                              s.axial_strain.size() - 1);
  return 1.0 - (1.0 - in.initial_porosity) / (1.0 - s.volumetric_strain[r]);
}

// indicators.csv: the indicator series over strain bins (§3.2, §5.4, §6.3, §7), each bin's
// statistics over its trailing window, and why a missing one is missing (§0.3: NaN, never 0).
void write_indicators(const fs::path& folder, const FailureInputs& in, const CrackPoints& cp,
                      const EventCatalogue& cat, const MagnitudeStats& ms, const D2Stats& d2,
                      const analysis::Stages& stages) {
  const auto& spec = in.spec;
  const auto min_events = static_cast<std::size_t>(spec.ae_min_events);
  const double e_end = in.series.axial_strain.empty() ? 0.0 : in.series.axial_strain.back();
  const double mc = ms.completeness.magnitude;
  analysis::CrackSeriesSettings css;
  css.bin_width = spec.ae_bin_width;
  css.window_bins = static_cast<std::size_t>(spec.ae_window_bins);
  const analysis::CrackSeries cs =
      analysis::crack_series(cp.strain, cp.shear, cp.energy, 0.0, e_end, css);
  std::string t =
      "axial_strain,cracks,tensile,shear,energy_j,cumulative_cracks,cumulative_tensile,"
      "cumulative_shear,shear_fraction,mc_var,ae_var_j2,b_value,b_events,b_window_strain,"
      "d2,d2_points,d2_window_strain,porosity,damage_index,stage,missing\n";
  const double window = spec.ae_bin_width * static_cast<double>(spec.ae_window_bins);
  for (std::size_t j = 0; j < cs.bin_end.size(); ++j) {
    poll(in, "computing the indicator series");
    const double e1 = cs.bin_end[j];
    double b_from = 0.0;
    const analysis::BValue bj = trailing_b_value(cat, mc, e1, window, min_events, b_from);
    // D2: crack midpoints in the trailing window, extended back to min_events cracks.
    std::size_t last = 0;
    while (last < cp.count && cp.strain[last] <= e1) ++last;
    std::size_t first = last;
    while (first > 0 && cp.strain[first - 1] > e1 - window) --first;
    if (last - first < min_events && last >= min_events) first = last - min_events;
    bool thinned = false;
    const std::vector<Vec3> pts(cp.position.begin() + static_cast<std::ptrdiff_t>(first),
                                cp.position.begin() + static_cast<std::ptrdiff_t>(last));
    const analysis::CorrelationDimension dj =
        analysis::correlation_dimension(thin(pts, kD2Cap, thinned), d2.settings);
    const double n = porosity_at(in, e1);
    std::string missing;
    const auto why = [&](const std::string& w) { missing += (missing.empty() ? "" : ";") + w; };
    if (!std::isfinite(cs.mc_var[j])) why("window_incomplete");
    if (std::isfinite(cs.mc_var[j]) && !std::isfinite(cs.shear_fraction[j]))
      why("shear_fraction:too_few_cracks");
    if (!bj.valid()) why("b_value:" + (std::isfinite(mc) ? bj.flag : ms.completeness.flag));
    for (const auto& f : dj.flags)
      if (!dj.valid()) why("d2:" + f);
    if (thinned) why("d2:subsampled");
    t += fmt::format("{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{}\n", g(e1),
                     cs.count[j], cs.tensile[j], cs.shear[j], g(cs.energy[j]), cs.cumulative[j],
                     cs.cumulative_tensile[j], cs.cumulative_shear[j], g(cs.shear_fraction[j]),
                     g(cs.mc_var[j]), g(cs.ae_var[j]), g(bj.b), bj.events,
                     g(bj.valid() ? e1 - b_from : kNaN), g(dj.d2), dj.points,
                     g(first < last ? e1 - std::min(e1 - window, cp.strain[first]) : kNaN), g(n),
                     g((n - in.initial_porosity) / in.initial_porosity),
                     stages.stage_of(e1 - 0.5 * css.bin_width), missing);
  }
  put(folder / "indicators.csv", t);
}

// Fragments (§9): connected components of the intact bonds, written to fragments.csv; returns
// their summary.
json fragments_summary(const fs::path& folder, const FailureInputs& in) {
  const analysis::FragmentResult f = analysis::find_fragments(
      in.sim.particles(),
      [&](const analysis::BondVisit& visit) { in.sim.for_each_intact_bond(visit); },
      in.spec.density_scaling, in.rock_particles);
  AtomicFileWriter file(folder / "fragments.csv");
  std::ostream& out = file.stream();
  out << "fragment_id,particles,mass_kg,volume_m3,x_m,y_m,z_m,fraction_of_largest,class\n";
  for (std::size_t k = 0; k < f.fragments.size(); ++k) {
    const auto& fr = f.fragments[k];
    const double frac = fr.mass / f.largest_mass;
    out << fmt::format("{},{},{},{},{},{},{},{},{}\n", k, fr.particles, g(fr.mass), g(fr.volume),
                       g(fr.centroid.x), g(fr.centroid.y), g(fr.centroid.z), g(frac),
                       frac < 0.1   ? "smallest"
                       : frac > 0.9 ? "biggest"
                                    : "intermediate");
  }
  file.commit();
  const auto cls = [](const analysis::ClassCount& c) {
    return json{{"count", c.count}, {"mass_kg", c.mass}};
  };
  return {{"count", f.fragments.size()},
          {"single_particle_debris", f.debris},
          {"largest_mass_kg", f.largest_mass},
          {"largest_fraction_of_total", f.largest_fraction},
          {"largest_particles", f.fragments.empty() ? 0 : f.fragments.front().particles},
          {"classes",
           {{"smallest_below_0.1_of_largest", cls(f.smallest)},
            {"intermediate", cls(f.intermediate)},
            {"biggest_above_0.9_of_largest", cls(f.biggest)}}},
          {"classes_without_debris",
           {{"smallest_below_0.1_of_largest", cls(f.smallest_no_debris)},
            {"intermediate", cls(f.intermediate_no_debris)},
            {"biggest_above_0.9_of_largest", cls(f.biggest_no_debris)}}},
          {"method", "connected components of intact bonds (union-find); walls ignored"}};
}

// The deformation stages (§8) with their cracks, modes, energies, events and b-values.
json stages_summary(const FailureInputs& in, const analysis::Stages& stages,
                    const EventCatalogue& cat, const MagnitudeStats& ms, std::size_t nc) {
  auto cracks = in.sim.cracks().reader();
  const auto& ctx = in.ae.crack_context();
  const std::vector<AeEvent>& ev = in.ae.events();
  const auto min_events = static_cast<std::size_t>(in.spec.ae_min_events);
  json js = json::array();
  for (int k = 1; k <= 4; ++k) {
    std::size_t n = 0, nt = 0, ns = 0, ne = 0;
    double en = 0.0, ef = 0.0;
    for (std::size_t c = 0; c < nc; ++c)
      if (stages.stage_of(ctx[c].axial_strain) == k) {
        ++n;
        (cracks[c].mode == CrackMode::Tensile ? nt : ns)++;
        en += cracks[c].energy.total();
        ef += ctx[c].fracture_energy;
      }
    std::vector<double> m_stage;
    for (std::size_t e = 0; e < ev.size(); ++e)
      if (stages.stage_of(ev[e].strain_first) == k) {
        ++ne;
        m_stage.push_back(cat.magnitude[e]);
      }
    const analysis::BValue bs =
        analysis::b_value(m_stage, ms.completeness.magnitude, 0.0, min_events);
    const double lo = k == 1   ? 0.0
                      : k == 2 ? stages.linear_limit
                      : k == 3 ? stages.peak
                               : stages.residual_start;
    const double hi =
        k == 1   ? stages.linear_limit
        : k == 2 ? stages.peak
        : k == 3 ? (std::isfinite(stages.residual_start) ? stages.residual_start : stages.end)
                 : stages.end;
    js.push_back({{"stage", analysis::stage_name(k)},
                  {"axial_strain_from", jnum(lo)},
                  {"axial_strain_to", jnum(hi)},
                  {"cracks", n},
                  {"tensile", nt},
                  {"shear", ns},
                  {"shear_fraction", n ? json(double(ns) / double(n)) : json(nullptr)},
                  {"released_energy_j", en},
                  {"fracture_energy_estimate_j", ef},
                  {"events", ne},
                  {"b_value", jnum(bs.b)},
                  {"b_value_flag", bs.flag}});
  }
  return {{"method",
           "docs/analysis.md §8: 5-sample smoothing, reference line over 20-50 % of the peak, 2 % "
           "deviation, end of drop at residual + 10 % of the drop"},
          {"linear_limit_strain", jnum(stages.linear_limit)},
          {"peak_strain", jnum(stages.peak)},
          {"residual_start_strain", jnum(stages.residual_start)},
          {"flags", stages.flags},
          {"by_stage", js}};
}

// The finite range of a list of values (NaN, NaN when none is finite).
std::array<double, 2> finite_range(const std::vector<double>& v) {
  double lo = kNaN, hi = kNaN;
  for (double x : v)
    if (std::isfinite(x)) {
      lo = std::isfinite(lo) ? std::min(lo, x) : x;
      hi = std::isfinite(hi) ? std::max(hi, x) : x;
    }
  return {lo, hi};
}

// Whether the b-value falls toward failure: its windows up to the peak (§5.4).
json b_value_before_peak(const FailureInputs& in, const MagnitudeStats& ms) {
  const analysis::BValueTrend t = analysis::b_value_trend(
      ms.windows, in.result.strain_at_peak, in.stress_strain && in.result.peak_reached);
  return {{"windows", t.windows},
          {"first_axial_strain", jnum(t.first_strain)},
          {"first_b", jnum(t.first_b)},
          {"at_peak_axial_strain", jnum(t.last_strain)},
          {"at_peak_b", jnum(t.last_b)},
          {"spearman_rho", jnum(t.spearman_rho)},
          {"flag", t.flag},
          {"method",
           "windows stamped at or before the peak strain; Spearman's rho of b against "
           "strain over them (at least 5; -1: b falls at every window)"}};
}

// The acoustic-emission block of summary.json.
json acoustic_emission_summary(const FailureInputs& in, const CrackPoints& cp,
                               const EventCatalogue& cat, const MagnitudeStats& ms,
                               const D2Stats& d2) {
  const auto& spec = in.spec;
  std::vector<double> b_valid;
  for (const auto& w : ms.windows)
    if (w.value.valid()) b_valid.push_back(w.value.b);
  const auto mw = finite_range(cat.magnitude), b = finite_range(b_valid),
             d = finite_range(d2.window_values);
  std::size_t tensile_src = 0, shear_src = 0, implosive_src = 0, ns = 0;
  for (const auto& s : cat.source) {
    if (s.zero) continue;
    (s.r_ratio > 30 ? tensile_src : s.r_ratio < -30 ? implosive_src : shear_src)++;
  }
  for (std::size_t k = 0; k < cp.count; ++k) ns += static_cast<std::size_t>(cp.shear[k]);
  std::string d2_flags;
  for (const auto& f : d2.all.flags) d2_flags += (d2_flags.empty() ? "" : ";") + f;
  if (d2.all_thinned) d2_flags += (d2_flags.empty() ? "" : ";") + std::string("subsampled");
  const std::size_t nc = cp.count;
  return {
      {"cracks", nc},
      {"events", cat.order.size()},
      {"largest_event_cracks", cat.largest},
      {"shear_fraction", nc ? json(double(ns) / double(nc)) : json(nullptr)},
      {"source_radius_m", in.ae.settings().source_radius},
      {"shear_wave_speed_m_s", in.ae.settings().shear_wave_speed},
      {"shear_wave_speed_method", in.wave_speed_method},
      {"event_duration_s", in.ae.duration()},
      {"magnitude", spec.ae_moment_tensors
                        ? "moment magnitude M_w = 2/3 log10 M0 + c"
                        : "energy magnitude 2/3 log10 E - 3.2 (moment tensors off)"},
      {"magnitude_constant", spec.ae_magnitude_constant},
      {"magnitude_range", {jnum(mw[0]), jnum(mw[1])}},
      {"zero_moment_events", cat.zero_moment},
      {"source_types_by_r_ratio",
       {{"tensile", tensile_src}, {"shear", shear_src}, {"implosive", implosive_src}}},
      {"completeness_magnitude", jnum(ms.completeness.magnitude)},
      {"completeness_flag", ms.completeness.flag},
      {"b_value",
       {{"b", jnum(ms.b_all.b)},
        {"sigma", jnum(ms.b_all.sigma)},
        {"a", jnum(ms.b_all.a)},
        {"events_above_completeness", ms.b_all.events},
        {"flag", ms.b_all.flag},
        {"method", "Aki-Utsu maximum likelihood above M_c (maximum curvature + 0.2)"}}},
      {"b_value_window_range", {jnum(b[0]), jnum(b[1])}},
      {"b_value_before_peak", b_value_before_peak(in, ms)},
      {"d2",
       {{"d2", jnum(d2.all.d2)},
        {"standard_error", jnum(d2.all.standard_error)},
        {"r2", jnum(d2.all.r2)},
        {"range_m", {jnum(d2.all.r_min), jnum(d2.all.r_max)}},
        {"points", d2.all.points},
        {"flags", d2_flags},
        {"of", "crack midpoints"}}},
      {"d2_window_range", {jnum(d[0]), jnum(d[1])}},
      {"energy",
       {{"released_by_breaks_j", cat.energy},
        {"fracture_energy_estimate_j", cat.fracture_energy},
        {"kinetic_energy_events_j", cat.kinetic_energy}}},
      {"files",
       {"events.csv", "indicators.csv", "b_value_windows.csv", "d2_windows.csv", "fragments.csv"}}};
}

// The ledger's terms in one history row, for the energy budget.
json ledger_row(const Table& hist, std::size_t r) {
  const auto v = [&](const char* c) { return hist.at(r, c); };
  const double bond = v("bond_tension_j") + v("bond_compression_j") + v("bond_shear_j") +
                      v("bond_bending_j") + v("bond_twisting_j");
  return json{{"axial_strain", v("axial_strain")},
              {"deviatoric_stress_pa", v("deviatoric_stress_pa")},
              {"external_work_j", work_in(hist, r)},
              {"bond_strain_j",
               {{"tension", v("bond_tension_j")},
                {"compression", v("bond_compression_j")},
                {"shear", v("bond_shear_j")},
                {"bending", v("bond_bending_j")},
                {"twisting", v("bond_twisting_j")},
                {"total", bond}}},
              {"contact_strain_j", v("contact_strain_j")},
              {"kinetic_j", v("kinetic_j")},
              {"friction_j", v("friction_j")},
              {"damping_j", v("local_damping_j") + v("viscous_damping_j")},
              {"released_by_breaks_j", v("released_by_breaks_j")},
              {"deleted_springs_j", v("deleted_springs_j")},
              {"residual_j", v("energy_residual_j")},
              {"residual_relative", v("energy_residual_relative")}};
}

// Continuum cross-checks of the energy budget (§2.1, §2.3): boundary work from the stress-strain
// record, and the elastic energy of the bulk modulus at the peak.
json continuum_estimates(const FailureInputs& in, const Table& hist, std::size_t ip) {
  const auto& s = in.series;
  const analysis::CompressionResult& an = in.result;
  const std::size_t last = hist.rows.size() - 1;
  double w_cont = 0.0;
  const double k_lat = in.sim.particles().planar() ? 1.0 : 2.0;
  for (std::size_t r = 1; r <= last; ++r) {
    const double s1a = hist.at(r - 1, "axial_stress_nominal_pa");
    const double s1b = hist.at(r, "axial_stress_nominal_pa");
    const double s3a = hist.at(r - 1, "confining_stress_pa");
    const double s3b = hist.at(r, "confining_stress_pa");
    w_cont += 0.5 * (s1a + s1b) * (s.axial_strain[r] - s.axial_strain[r - 1]) +
              k_lat * 0.5 * (s3a + s3b) * (s.lateral_strain[r] - s.lateral_strain[r - 1]);
  }
  w_cont *= in.volume0;
  const double w_engine = work_in(hist, last) - work_in(hist, 0);
  const double E = an.e_t50.valid ? an.e_t50.slope : kNaN, nu = an.poisson;
  const double s3 = confining_stress(in.spec), s1 = an.sigma1_at_peak, q = an.peak_deviatoric;
  const double ue = analysis::elastic_energy_density(s1, s3, E, nu);
  const double ue_dev = analysis::deviatoric_elastic_energy_density(q, s3, E, nu);
  const auto stored = [&](std::size_t r) {
    return hist.at(r, "bond_tension_j") + hist.at(r, "bond_compression_j") +
           hist.at(r, "bond_shear_j") + hist.at(r, "bond_bending_j") +
           hist.at(r, "bond_twisting_j") + hist.at(r, "contact_strain_j");
  };
  return {{"external_work_from_stress_strain_j", w_cont},
          {"external_work_engine_since_loading_j", w_engine},
          {"elastic_energy_density_at_peak_j_m3", jnum(ue)},
          {"elastic_energy_at_peak_j", jnum(ue * in.volume0)},
          {"deviatoric_elastic_energy_at_peak_j", jnum(ue_dev * in.volume0)},
          {"differential_shortcut_q2_over_2e_j", jnum(q * q / (2 * E) * in.volume0)},
          {"stored_strain_energy_at_peak_j", stored(ip) - stored(0)},
          {"sample_volume_m3", in.volume0},
          {"method",
           "W = V0 (int sigma_1 d eps_a + k sigma_3 d eps_lat) with nominal stresses; "
           "u_e = [sigma_1^2 + 2 sigma_3^2 - 2 nu (2 sigma_1 sigma_3 + sigma_3^2)] / 2E with "
           "E_t50 and nu of this test (docs/analysis.md §2.3)"}};
}

// The energy budget at the test's landmarks (§2): crack initiation (5 % of the cracks at the
// peak), crack damage (largest volumetric strain before the peak), the peak and the end. Null
// when history.csv does not match the series.
json energy_budget_summary(const fs::path& folder, const FailureInputs& in) {
  const Table hist = read_table(folder / "history.csv");
  const auto& s = in.series;
  if (hist.rows.empty() || hist.rows.size() != s.axial_strain.size()) return nullptr;
  const std::size_t last = hist.rows.size() - 1;
  std::size_t ip = 0, ici = last, icd = 0;
  for (std::size_t k = 0; k < s.deviatoric.size(); ++k)
    if (s.deviatoric[k] > s.deviatoric[ip]) ip = k;
  const double cracks_peak = s.broken_bonds[ip];
  for (std::size_t k = 0; k <= ip; ++k)
    if (cracks_peak > 0 && s.broken_bonds[k] >= 0.05 * cracks_peak) {
      ici = k;
      break;
    }
  for (std::size_t k = 0; k <= ip; ++k)
    if (s.volumetric_strain[k] > s.volumetric_strain[icd]) icd = k;
  const double rel_end = hist.at(last, "energy_residual_relative");
  json landmarks = {{"at_end", ledger_row(hist, last)}};
  if (in.stress_strain)
    landmarks.update(json{{"at_crack_initiation", ledger_row(hist, ici)},
                          {"at_crack_damage", ledger_row(hist, icd)},
                          {"at_peak", ledger_row(hist, ip)}});
  double rel_max = 0.0;
  const double w_final = work_in(hist, last);
  for (std::size_t r = 0; r <= last; ++r)
    if (std::abs(work_in(hist, r)) > 0.01 * std::abs(w_final))
      rel_max = std::max(rel_max, std::abs(hist.at(r, "energy_residual_relative")));
  json out = {{"convention",
               "cumulative from the engine's first step (consolidation included); residual = "
               "work in - change of stored energy - dissipated (docs/physics.md §2.4)"},
              {"residual_relative_at_end", rel_end},
              {"residual_relative_max_after_1pct_work", rel_max},
              {"classification", rel_max <= 0.01   ? "good"
                                 : rel_max <= 0.05 ? "warning"
                                                   : "energy_balance_failed"}};
  out.update(landmarks);
  if (in.stress_strain) out["continuum_estimates"] = continuum_estimates(in, hist, ip);
  return out;
}

}  // namespace

json write_failure_analysis(const fs::path& folder, const FailureInputs& in) {
  const analysis::CompressionSeries& s = in.series;
  // Stages belong to a stress-strain curve; other tests leave every crack's stage undefined.
  const analysis::Stages stages =
      in.stress_strain ? analysis::find_stages(s.axial_strain, s.deviatoric, in.result.residual,
                                               in.result.peak_reached)
                       : analysis::Stages{};
  // A signal stops the analysis between stages (and between the windows of its longest ones).
  const char* stage = "analysing the failure";
  poll(in, stage);
  const CrackPoints cp = crack_points(in);
  const EventCatalogue cat = catalogue_events(in);
  poll(in, stage);
  write_events_csv(folder, in, cat, stages);
  write_crack_catalogue(folder, in, cat, stages, cp.count);
  const MagnitudeStats ms = frequency_magnitude(folder, in, cat);
  poll(in, stage);
  const D2Stats d2 = correlation_dimensions(folder, in, cp);
  write_indicators(folder, in, cp, cat, ms, d2, stages);
  poll(in, stage);
  json out;
  out["fragments"] = fragments_summary(folder, in);
  if (in.stress_strain) out["stages"] = stages_summary(in, stages, cat, ms, cp.count);
  out["acoustic_emission"] = acoustic_emission_summary(in, cp, cat, ms, d2);
  if (json budget = energy_budget_summary(folder, in); !budget.is_null())
    out["energy_budget"] = std::move(budget);
  return out;
}

}  // namespace breccia
