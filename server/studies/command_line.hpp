#pragma once
// The study launcher's command line (serve --study-launcher "mpirun -np 16 --hostfile H").
#include <string>
#include <vector>

namespace rover::studies {

// A launcher string split into argv the way a shell splits words, without a shell: blanks
// separate, '…' and "…" quote, a backslash escapes the next character. Throws on an open quote.
std::vector<std::string> splitCommandLine(const std::string& line);

}  // namespace rover::studies
