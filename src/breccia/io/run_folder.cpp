#include "breccia/io/run_folder.hpp"

#include <fmt/chrono.h>
#include <fmt/format.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <limits>
#include <nlohmann/json.hpp>
#include <sstream>
#include <thread>

#include "breccia/core/error.hpp"
#include "breccia/core/format.hpp"
#include "breccia/core/parallel.hpp"
#include "breccia/core/text_file.hpp"
#include "breccia/io/json_view.hpp"

namespace breccia {

namespace fs = std::filesystem;
using json = nlohmann::json;

std::string machine_description() {
  std::string cpu = "unknown CPU";
  std::ifstream info("/proc/cpuinfo");
  for (std::string line; std::getline(info, line);)
    if (line.rfind("model name", 0) == 0) {
      cpu = line.substr(line.find(':') + 2);
      break;
    }
  char host[256] = "unknown";
  gethostname(host, sizeof host - 1);
  // The threads this process runs on (engine.threads, --threads or OMP_NUM_THREADS) and the
  // machine's: a timing means little without both.
  return fmt::format("{}; {} threads used of {} hardware threads; host {}", cpu, max_threads(),
                     std::thread::hardware_concurrency(), host);
}

void write_json(const fs::path& p, const json& j) {
  write_file_atomically(p, j.dump(2) + "\n");  // a reader never sees half a manifest
}

std::string folder_safe_name(const std::string& name) {
  std::string safe;
  for (char c : name) safe += (std::isalnum(static_cast<unsigned char>(c)) || c == '-') ? c : '_';
  return safe;
}

fs::path make_folder(const ExperimentSpec& spec, const std::string& suffix) {
  const auto now = std::chrono::system_clock::now();
  const std::string stamp =
      fmt::format("{:%Y%m%d-%H%M%S}", fmt::localtime(std::chrono::system_clock::to_time_t(now)));
  const std::string base =
      (fs::path(spec.output_directory) / (stamp + "-" + folder_safe_name(spec.name))).string();
  std::error_code ec;
  fs::create_directories(spec.output_directory.empty() ? "." : spec.output_directory, ec);
  if (ec)
    throw InputError(spec.output_directory, "output.directory", spec.output_directory,
                     "cannot create the folder: " + ec.message());
  // create_directory is atomic: of two runs started in the same second (two sweeps of one
  // experiment, say), one gets the name and the other the next free one.
  for (int k = 1;; ++k) {
    const fs::path p = base + (k == 1 ? "" : "-" + std::to_string(k)) + suffix;
    if (fs::create_directory(p, ec)) return p;
    if (ec)
      throw InputError(p.string(), "output.directory", spec.output_directory,
                       "cannot create the run folder: " + ec.message());
  }
}

void make_plot(const fs::path& folder, const std::function<void(const std::string&)>& log) {
  if (!plot_run(folder.string()))
    log("warning: no stress_strain.png (see " + (folder / "plot.log").string() + ")");
  if (!write_report(folder.string()))
    log("warning: no report.html (see " + (folder / "report.log").string() + ")");
}

namespace {

std::string mpa(const JsonView& j, const char* key) {
  const auto v = j.maybe_number(key);
  return v ? fmt::format("{:.2f} MPa", *v * 1e-6) : "n/a";
}
std::string gpa(const JsonView& j, const char* key) {
  const auto v = j.maybe_number(key);
  return v ? fmt::format("{:.2f} GPa", *v * 1e-9) : "n/a";
}
std::string plain(const JsonView& j, const char* key, const char* f = "{:.3g}") {
  const auto v = j.maybe_number(key);
  return v ? fmt::format(fmt::runtime(f), *v) : "n/a";
}
// A two-number range ("a to b"), n/a when absent.
std::string range(const JsonView& j, const char* key) {
  const auto r = j.elements(key);
  if (r.size() != 2 || r[0].raw().is_null() || r[1].raw().is_null()) return "n/a";
  return fmt::format("{:.2f} to {:.2f}", r[0].as_number(), r[1].as_number());
}

// The keys every summary (or sweep.json) is written with: a file without them is not one that
// Breccia wrote whole, and is named rather than summarised as a page of n/a.
void require_keys(const JsonView& j, std::initializer_list<const char*> keys) {
  for (const char* k : keys) (void)j.at(k);
}

std::string summarise_sweep(const fs::path& file) {
  const json doc = read_json_object(file.string());
  const JsonView j(doc, file.string());
  require_keys(j, {"experiment", "status", "runs"});
  std::string s = fmt::format("sweep {} ({})\n", j.text("experiment", ""), j.text("status", ""));
  if (j.text("variable", "confining_stress") == "strain_rate") {
    s += "  rate (1/s)   peak q (MPa)   E_t50 (GPa)   cracks   damage ratio (%)\n";
    for (const JsonView& r : j.elements("runs"))
      s += fmt::format(
          "  {:>10.4g}   {:>12.2f}   {:>11}   {:>6}   {:>16.2f}\n",
          r.maybe_number("strain_rate_per_s").value_or(r.number("strain_rate_target_per_s")),
          r.maybe_number("peak_deviatoric_stress_pa").value_or(0.0) * 1e-6,
          gpa(r, "youngs_modulus_pa"), r.maybe_number("cracks").value_or(0.0),
          r.maybe_number("damage_ratio_percent").value_or(0.0));
    if (const auto f = j.find("rate_dependence"))
      s += f->flag("valid", false)
               ? fmt::format("UCS = a exp(b rate): a {}, b {} s (rms {})\n", mpa(*f, "a_pa"),
                             plain(*f, "b_s", "{:.4g}"), mpa(*f, "rms_residual_pa"))
               : "rate law: no fit (" + f->text("flag", "") + ")\n";
    return s;
  }
  const std::string variable = j.text("variable", "confining_stress");
  if (variable != "confining_stress") {
    s += fmt::format("  {:>16}   status      cracks   scaled   fragments\n", variable);
    for (const JsonView& r : j.elements("runs"))
      s += fmt::format("  {:>16}   {:<9}   {:>6}   {:>6}   {:>9}\n", r.text("value", "?"),
                       r.text("status", "?"), plain(r, "cracks", "{:.0f}"),
                       plain(r, "cracks_scaled", "{:.2f}"), plain(r, "fragments", "{:.0f}"));
    return s;
  }
  s += "  sigma3 (MPa)   peak q (MPa)   sigma1 (MPa)   E_t50 (GPa)   cracks\n";
  for (const JsonView& r : j.elements("runs"))
    s += fmt::format("  {:>12.2f}   {:>12.2f}   {:>12.2f}   {:>11}   {:>6}\n",
                     r.number("confining_stress_pa") * 1e-6,
                     r.maybe_number("peak_deviatoric_stress_pa").value_or(0.0) * 1e-6,
                     r.maybe_number("sigma1_at_peak_pa").value_or(0.0) * 1e-6,
                     gpa(r, "youngs_modulus_pa"), r.maybe_number("cracks").value_or(0.0));
  if (const auto mc = j.find("mohr_coulomb"))
    s += mc->flag("valid", false)
             ? fmt::format("Mohr-Coulomb: cohesion {}, friction angle {} deg, UCS {} (R^2 {})\n",
                           mpa(*mc, "cohesion_pa"), plain(*mc, "friction_angle_deg", "{:.1f}"),
                           mpa(*mc, "ucs_intercept_pa"), plain(*mc, "r2"))
             : "Mohr-Coulomb: no fit (" + mc->text("flag", "") + ")\n";
  if (const auto hb = j.find("hoek_brown"))
    s += hb->flag("valid", false)
             ? fmt::format("Hoek-Brown: sigma_ci {}, m_i {} (rms {})\n", mpa(*hb, "sigma_ci_pa"),
                           plain(*hb, "m_i"), mpa(*hb, "rms_residual_pa"))
             : "Hoek-Brown: no fit (" + hb->text("flag", "") + ")\n";
  return s;
}

namespace {

// "b before the peak: from 8.54 at 0.456 % strain to 2.57 at 0.573 % over 71 windows, Spearman
// rho -0.91" (the first window's b and strain, then the last before the peak), or why there is
// no such line.
std::string b_before_peak_text(const JsonView& ae) {
  const auto t = ae.find("b_value_before_peak");
  if (!t) return "";
  const std::string flag = t->text("flag", "");
  if (flag == "no_peak") return "";
  if (flag == "no_window_before_peak")
    return "\n  b before the peak: no window (fewer events above M_c precede the peak than a "
           "window holds)";
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const auto pct = [&](const char* key) { return 100.0 * t->maybe_number(key).value_or(nan); };
  std::string s = fmt::format(
      "\n  b before the peak: from {:.2f} at {:.3f} % strain to {:.2f} at {:.3f} % over {} "
      "window{}",
      t->maybe_number("first_b").value_or(nan), pct("first_axial_strain"),
      t->maybe_number("at_peak_b").value_or(nan), pct("at_peak_axial_strain"),
      plain(*t, "windows", "{:.0f}"), t->maybe_number("windows").value_or(0.0) == 1.0 ? "" : "s");
  return s + (t->has("spearman_rho")
                  ? fmt::format(", Spearman rho {:.2f}", t->number("spearman_rho"))
                  : " (too few for a trend)");
}

}  // namespace

std::string summarise_acoustic_emission(const JsonView& ae) {
  std::string b_text = "n/a";
  if (const auto b = ae.find("b_value"))
    b_text = b->has("b") ? fmt::format("{:.2f} +- {:.2f}", b->number("b"),
                                       b->maybe_number("sigma").value_or(0.0))
                         : "n/a (" + b->text("flag", "") + ")";
  std::string d2 = "n/a";
  if (const auto d = ae.find("d2")) d2 = plain(*d, "d2", "{:.2f}");
  return fmt::format(
             "\n  AE: {} events (largest {} cracks), M_w {}, b = {} (windows {}), D2 = {} (windows "
             "{}); shear fraction {}",
             plain(ae, "events", "{:.0f}"), plain(ae, "largest_event_cracks", "{:.0f}"),
             range(ae, "magnitude_range"), b_text, range(ae, "b_value_window_range"), d2,
             range(ae, "d2_window_range"), plain(ae, "shear_fraction", "{:.3f}")) +
         b_before_peak_text(ae);
}

namespace {

// The strength line of a stress-strain test: a tensile test's strength as the test reads it
// (its tensile_strength_reading: name and formula), with the modulus where its rows are the
// sample's stress and strain (sample_moduli), else the peak deviatoric stress.
std::string strength_line(const JsonView& j) {
  const auto reading = j.find("tensile_strength_reading");
  if (!reading)
    return fmt::format("  peak q {} at axial strain {}; E_t50 {}; Poisson {}\n",
                       mpa(j, "peak_deviatoric_stress_pa"),
                       plain(j, "axial_strain_at_peak", "{:.5f}"), gpa(j, "youngs_modulus_pa"),
                       plain(j, "poisson_ratio"));
  return fmt::format(
      "  {} sigma_t = {} {} (peak force {} N) at strain {}{}\n", reading->text("name", ""),
      reading->text("formula", ""), mpa(j, "tensile_strength_pa"),
      plain(j, "peak_force_n", "{:.4g}"), plain(j, "axial_strain_at_peak", "{:.5f}"),
      reading->has("sample_moduli")
          ? "; E_t50 " + gpa(j, "youngs_modulus_pa") + ", Poisson " + plain(j, "poisson_ratio")
          : std::string());
}

}  // namespace

std::string summarise_run(const fs::path& file) {
  const json doc = read_json_object(file.string());
  const JsonView j(doc, file.string());
  require_keys(j, {"experiment", "status", "test"});
  // Tests that are not read as stress-strain curves write their own headline lines.
  const auto own = j.find(j.text("test_kind", ""));
  const bool headline = own && own->has("headline");
  std::string s = fmt::format("{}: {}{} ({}; {})\n", j.text("experiment", ""), j.text("test", ""),
                              headline ? "" : ", sigma3 = " + mpa(j, "confining_stress_pa"),
                              j.text("status", ""), j.text("stop_reason", ""));
  if (headline) {
    for (const JsonView& line : own->elements("headline")) s += "  " + line.as_text() + "\n";
  } else {
    s += strength_line(j);
    s += fmt::format("  crack initiation {}, crack damage {}, residual {}\n",
                     mpa(j, "crack_initiation_stress_pa"), mpa(j, "crack_damage_stress_pa"),
                     mpa(j, "residual_strength_pa"));
  }
  // A flat joint's elements break one by one: its bonded elements are the crack sites.
  const std::string sites =
      j.has("bond_sites_initial") && j.number("bond_sites_initial") != j.number("bonds_initial")
          ? " (" + plain(j, "bond_sites_initial", "{:.0f}") + " bonded elements)"
          : "";
  s += fmt::format("  {} particles, {} bonds{}; {} cracks ({} tensile, {} shear)\n",
                   plain(j, "particles", "{:.0f}"), plain(j, "bonds_initial", "{:.0f}"), sites,
                   plain(j, "bonds_broken", "{:.0f}"), plain(j, "cracks_tensile", "{:.0f}"),
                   plain(j, "cracks_shear", "{:.0f}"));
  if (const auto fr = j.find("fragments"))
    if (const auto cl = fr->find("classes_without_debris")) {
      const auto count = [&](const char* k) {
        const auto c = cl->find(k);
        return c ? plain(*c, "count", "{:.0f}") : std::string("n/a");
      };
      s += fmt::format(
          "  fragments: {} ({} single grains); largest {} of the mass; without single grains: {} "
          "below 0.1 of the largest, {} between, {} above 0.9\n",
          plain(*fr, "count", "{:.0f}"), plain(*fr, "single_particle_debris", "{:.0f}"),
          plain(*fr, "largest_fraction_of_total", "{:.3f}"), count("smallest_below_0.1_of_largest"),
          count("intermediate"), count("biggest_above_0.9_of_largest"));
    }
  if (const auto cp = j.find("crack_pattern")) {
    const auto q = cp->elements("quarter_shares_along_axis");
    if (q.size() == 4)
      s += fmt::format("  cracks per quarter along the axis: {:.2f} {:.2f} {:.2f} {:.2f}\n",
                       q[0].as_number(), q[1].as_number(), q[2].as_number(), q[3].as_number());
  }
  if (const auto qs = j.find("quasi_static"))
    s += fmt::format("  quasi-static: {} (platen imbalance {}, kinetic/strain {})",
                     qs->flag("ok", false) ? "yes" : "NO",
                     plain(*qs, "max_platen_force_imbalance_before_peak"),
                     plain(*qs, "max_kinetic_to_strain_energy_before_peak"));
  if (j.maybe_number("confining_stress_pa").value_or(0.0) > 0.0)
    if (const auto ce = j.find("confining_stress_error"))
      s += fmt::format("; confining error before peak {:.2f} %",
                       100 * ce->maybe_number("max_relative_before_peak").value_or(0.0));
  if (const auto ae = j.find("acoustic_emission")) s += summarise_acoustic_emission(*ae);
  if (const auto eb = j.find("energy_budget"))
    s += fmt::format("\n  energy balance: {} (largest relative residual {})",
                     eb->text("classification", "n/a"),
                     plain(*eb, "residual_relative_max_after_1pct_work", "{:.2e}"));
  s += fmt::format("\n  {} steps in {} s ({} particle-steps/s", plain(j, "steps", "{:.0f}"),
                   plain(j, "wall_seconds", "{:.1f}"), plain(j, "particle_steps_per_second"));
  if (const auto loop = j.find("loading_loop"))
    s += fmt::format("; loading loop {} steps in {} s, {} particle-steps/s",
                     plain(*loop, "steps", "{:.0f}"), plain(*loop, "seconds", "{:.1f}"),
                     plain(*loop, "particle_steps_per_second"));
  s += ")\n";
  for (const JsonView& w : j.elements("warnings")) s += "  warning: " + w.as_text() + "\n";
  return s;
}

}  // namespace

namespace {
// The report and plots are modules of the Python package (python/breccia), which the build
// copies beside its engine module: run them with Debian's interpreter; their output goes to
// `log_name` in the folder, which is removed when they succeed.
bool run_module(const char* module, const std::string& folder, const char* log_name) {
  const fs::path logf = fs::path(folder) / log_name;
  const std::string cmd =
      fmt::format("PYTHONPATH='{}' /usr/bin/python3 -m breccia.{} '{}' > '{}' 2>&1",
                  BRECCIA_PYTHON_DIR, module, folder, logf.string());
  if (std::system(cmd.c_str()) != 0) return false;
  fs::remove(logf);
  return true;
}
}  // namespace

bool run_python_module(const std::string& module, const std::string& folder,
                       const std::string& log_name) {
  return run_module(module.c_str(), folder, log_name.c_str());
}

int run_python_command(const std::string& module, const std::vector<std::string>& args) {
  // Single-quoted for the shell, with each ' written as '\''.
  auto quoted = [](const std::string& a) {
    std::string q = "'";
    for (char c : a) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
    return q + "'";
  };
  std::string cmd = fmt::format("PYTHONPATH={} /usr/bin/python3 -m breccia.{}",
                                quoted(BRECCIA_PYTHON_DIR), module);
  for (const std::string& a : args) cmd += " " + quoted(a);
  const int status = std::system(cmd.c_str());
  if (status == -1) return 1;
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
}

bool plot_run(const std::string& folder) {
  return run_module("plots", folder, "plot.log");
}

bool write_report(const std::string& folder) {
  return run_module("report", folder, "report.log");
}

namespace {

// The last complete row of a CSV table as column -> text; empty when it has no row.
std::vector<std::pair<std::string, std::string>> last_row(const fs::path& csv) {
  std::ifstream in(csv, std::ios::binary);
  std::string header;
  if (!std::getline(in, header)) return {};
  // Only the tail is read: a long run's history has many rows.
  const auto size = static_cast<std::streamoff>(fs::file_size(csv));
  const std::streamoff start =
      std::max<std::streamoff>(static_cast<std::streamoff>(header.size()) + 1, size - 65536);
  in.seekg(start);
  std::string line, last;
  while (std::getline(in, line))
    if (!line.empty() && !in.eof()) last = line;  // a row without its newline is being written
  std::vector<std::pair<std::string, std::string>> row;
  std::stringstream hs(header), ls(last);
  for (std::string name, value; std::getline(hs, name, ',') && std::getline(ls, value, ',');)
    row.emplace_back(name, value);
  return last.empty() ? decltype(row){} : row;
}

// Where an unfinished run stands: its manifest's status and its history's last row.
std::string summarise_unfinished_run(const fs::path& f) {
  const fs::path mpath = f / "manifest.json";
  const json m = read_json_object(mpath.string());
  const JsonView v(m, mpath.string());
  std::string s = fmt::format("{}: {}", f.filename().string(), v.text("status", "unknown"));
  if (v.has("stop_reason")) s += " (" + v.text("stop_reason", "") + ")";
  std::string at;
  for (const auto& [name, value] : last_row(f / "history.csv"))
    if (name == "step" || name == "time_s" || name == "axial_strain" ||
        name == "deviatoric_stress_pa" || name == "broken_bonds")
      at += fmt::format("{}{} {}", at.empty() ? "" : ", ", name, value);
  s += at.empty() ? "; no row recorded yet" : "; last row: " + at;
  if (const auto cp = v.find("checkpoint"))
    s += fmt::format("; checkpoint at step {}", plain(*cp, "step", "{:.0f}"));
  return s + "\n";
}

// A sweep without sweep.json (still running, or killed): its plan and its runs so far.
std::string summarise_unfinished_sweep(const fs::path& f) {
  const fs::path ppath = f / "sweep-plan.json";
  const json p = read_json_object(ppath.string());
  const JsonView v(p, ppath.string());
  std::string values;
  for (const JsonView& x : v.elements("values")) values += " " + x.as_text();
  const std::string kind = v.text("kind", "");
  std::string s =
      fmt::format("sweep {} (unfinished: no sweep.json yet)\n  {} over{} ({} runs planned)\n",
                  f.filename().string(), kind == "parameter" ? v.text("key", "") : kind, values,
                  v.elements("values").size());
  std::vector<fs::path> runs;
  for (const fs::directory_entry& d : fs::directory_iterator(f))
    if (d.is_directory() && fs::exists(d.path() / "manifest.json")) runs.push_back(d.path());
  std::sort(runs.begin(), runs.end());
  for (const fs::path& r : runs) {
    const json m = read_json_object((r / "manifest.json").string());
    const bool complete =
        JsonView(m, (r / "manifest.json").string()).text("status", "") == "complete";
    s += "  " + (complete ? r.filename().string() + ": complete\n" : summarise_unfinished_run(r));
  }
  s += fmt::format(
      "  {} of {} runs started; once it has stopped, `breccia resume {}` finishes "
      "it\n",
      runs.size(), v.elements("values").size(), f.string());
  return s;
}

// Rows of a CSV table (not counting its header).
std::size_t csv_rows(const fs::path& csv) {
  std::ifstream in(csv);
  std::size_t n = 0;
  for (std::string line; std::getline(in, line);) n += !line.empty();
  return n > 0 ? n - 1 : 0;
}

// A calibration folder: its status, its trials and, once complete, the verdict per target.
std::string summarise_calibration(const fs::path& f, const JsonView& manifest) {
  std::string s = fmt::format("calibration {} ({})\n", manifest.text("name", f.filename().string()),
                              manifest.text("status", "unknown"));
  if (manifest.has("error")) s += "  error: " + manifest.text("error", "") + "\n";
  s += fmt::format("  {} trials so far (convergence.csv)\n", csv_rows(f / "convergence.csv"));
  const fs::path rpath = f / "record.json";
  if (!fs::exists(rpath)) {
    if (manifest.text("status", "") != "complete")
      s += "  no verdict yet: run the same `breccia calibrate` command again to continue it\n";
    return s;
  }
  const json record = read_json_object(rpath.string());
  const JsonView r(record, rpath.string());
  s += "  target                         lab        achieved (mean +/- sd, n)   error    verdict\n";
  for (const JsonView& v : r.elements("verdicts")) {
    const bool relative = v.flag("relative", true);
    const std::string unit = v.text("unit", "");
    const auto error = v.maybe_number("error");
    s += fmt::format("  {:<24} {:>12.4g} {:>13} +/- {:<9} ({})   {:>8}   {}\n",
                     v.text("target", "?"), v.number("value"), plain(v, "mean", "{:.4g}"),
                     plain(v, "sd", "{:.2g}"), plain(v, "samples", "{:.0f}"),
                     !error                        ? std::string("n/a")
                     : relative                    ? fmt::format("{:+.1f} %", 100 * *error)
                     : unit == "-" || unit.empty() ? fmt::format("{:+.3f}", *error)
                                                   : fmt::format("{:+.2f} {}", *error, unit),
                     v.flag("met", false) ? "met" : "MISSED");
  }
  s += fmt::format("  parameters: {}\n", (f / "material.toml").string());
  return s;
}

}  // namespace

std::string summarise_folder(const std::string& folder) {
  const fs::path f(folder);
  if (!fs::is_directory(f)) throw InputError(folder, "", "", "not a folder");
  if (fs::exists(f / "manifest.json") && fs::exists(f / "calibration.toml")) {
    const json m = read_json_object((f / "manifest.json").string());
    const JsonView v(m, (f / "manifest.json").string());
    if (v.text("kind", "") == "calibration") return summarise_calibration(f, v);
  }
  if (fs::exists(f / "sweep.json")) return summarise_sweep(f / "sweep.json");
  if (fs::exists(f / "sweep-plan.json")) return summarise_unfinished_sweep(f);
  if (fs::exists(f / "summary.json")) return summarise_run(f / "summary.json");
  if (fs::exists(f / "manifest.json")) return summarise_unfinished_run(f);
  throw InputError(folder, "summary.json", "(missing)",
                   "a run folder (summary.json or manifest.json) or a sweep folder (sweep.json "
                   "or sweep-plan.json)");
}

}  // namespace breccia
