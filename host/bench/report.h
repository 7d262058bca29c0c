// The files of a bench run: DIR/results.json (the machine-readable record:
// command line, machine, options, one record per row) and DIR/results.md
// (Markdown tables generated from that JSON alone, so that runs of different
// studies merged into one results.json render together).
#pragma once

#include <string>

#include <nlohmann/json.hpp>

namespace cr::bench {

// Reads DIR/results.json when it exists and parses (else an empty object):
// a study run (--scaling, --hard) replaces its own section and keeps the rest.
nlohmann::json LoadResults(const std::string& dir);

void WriteResults(const std::string& dir, const nlohmann::json& results);

// The whole Markdown report.
std::string ResultsMarkdown(const nlohmann::json& results);

// The comparison with Embree (docs/BENCHMARKS.md): per scene and ray kind,
// our fastest robust configuration, Embree's fastest, and the ratio of their
// speeds (>= 1: ours is faster). Markdown table, "" without Embree rows.
std::string EmbreeComparisonMarkdown(const nlohmann::json& rows, const std::vector<std::string>& kinds);

}  // namespace cr::bench
