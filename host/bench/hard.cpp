// Placeholder until the hard-case suite lands (tests/hard/).
#include "bench/hard.h"

#include "core/error.h"

namespace cr {

std::vector<HardCaseResult> RunHardSuite(const HardOptions&) { throw RuntimeError("bench --hard: not implemented yet"); }

std::string HardTableMarkdown(const std::vector<HardCaseResult>&) { return ""; }

}  // namespace cr
