// SPDX-License-Identifier: Apache-2.0
#include "panoptes/tune/tune_plot.h"

#include <chrono>
#include <fstream>
#include <iomanip>
#include <sstream>
#include <stdexcept>
#include <thread>

#include "panoptes/process.h"

namespace panoptes::tune {

namespace {

// argv: csv png title cost_label right_axis_column. One panel per searched parameter (the CSV
// columns between "varied" and "cost"); the samples where that parameter was varied, by sweep,
// joined in order of value; the chosen value (lowest cost) marked.
constexpr const char* kPlotScript = R"PY(
import csv, sys
import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt
path, png, title, cost_label, right = sys.argv[1:6]
with open(path) as f:
    rows = list(csv.DictReader(f))
cols = list(rows[0].keys())
params = cols[cols.index("varied") + 1:cols.index("cost")]
best = min(rows, key=lambda r: float(r["cost"]))
fig, axes = plt.subplots(1, len(params), figsize=(5.2 * len(params), 4.2), squeeze=False)
for ax, p in zip(axes[0], params):
    sweeps = sorted({int(r["sweep"]) for r in rows if r["varied"] == p})
    for s in sweeps:
        pts = sorted((float(r[p]), float(r["cost"]), float(r[right]) if right else None)
                     for r in rows if r["varied"] == p and int(r["sweep"]) == s)
        ax.plot([q[0] for q in pts], [q[1] for q in pts], "o-", ms=3, label="criterion, sweep %d" % (s + 1))
        if right:
            if not hasattr(ax, "twin"):
                ax.twin = ax.twinx()
                ax.twin.set_ylabel(right)
            ax.twin.plot([q[0] for q in pts], [q[2] for q in pts], "s--", ms=3, color="C%d" % (s + 3),
                         label="%s, sweep %d" % (right, s + 1))
    ax.axvline(float(best[p]), color="k", lw=0.8, ls=":", label="chosen")
    ax.set_xscale("log")
    ax.set_xlabel(p)
    ax.set_ylabel(cost_label)
    ax.grid(True, which="both", alpha=0.3)
    handles, labels = ax.get_legend_handles_labels()
    if right and hasattr(ax, "twin"):
        h2, l2 = ax.twin.get_legend_handles_labels()
        handles, labels = handles + h2, labels + l2
    ax.legend(handles, labels, fontsize=7)
fig.suptitle(title)
fig.tight_layout()
fig.savefig(png, dpi=100)
)PY";

}  // namespace

void write_curve_csv(const std::filesystem::path& csv, const SearchResult& result,
                     const std::vector<std::string>& parameters,
                     const std::vector<std::string>& extra_names) {
  std::ofstream out(csv);
  if (!out) throw std::runtime_error(csv.string() + ": cannot write");
  out << "index,sweep,varied";
  for (const auto& name : parameters) out << ',' << name;
  out << ",cost";
  for (const auto& name : extra_names) out << ',' << name;
  out << '\n' << std::setprecision(9);
  for (const auto& sample : result.samples) {
    out << sample.index << ',' << sample.sweep << ',' << sample.varied;
    for (const double value : sample.values) out << ',' << value;
    out << ',' << sample.cost;
    for (const double extra : sample.extras) out << ',' << extra;
    out << '\n';
  }
  if (!out) throw std::runtime_error(csv.string() + ": write failed");
}

void write_curve_png(const std::filesystem::path& csv, const std::filesystem::path& png,
                     const std::string& title, const std::string& cost_label,
                     const std::string& right_axis_column) {
  const std::filesystem::path log = png.string() + ".log";
  std::filesystem::remove(png);
  ChildProcess python("python3",
                      {"/usr/bin/python3", "-c", kPlotScript, csv.string(), png.string(), title, cost_label,
                       right_axis_column},
                      log);
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(120);
  while (python.running() && std::chrono::steady_clock::now() < deadline)
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  const int code = python.stop();
  std::ifstream log_in(log);
  std::stringstream text;
  text << log_in.rdbuf();
  if (code != 0 || !std::filesystem::exists(png)) {
    throw std::runtime_error(png.string() + ": /usr/bin/python3 with matplotlib failed (exit " +
                             std::to_string(code) + "): " + text.str());
  }
  std::filesystem::remove(log);
}

}  // namespace panoptes::tune
