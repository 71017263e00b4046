#define DOCTEST_CONFIG_IMPLEMENT
#include <doctest/doctest.h>

#include <string>
#include <vector>

#include "server/jail/import_worker.hpp"

// The servers under test start their import workers as this executable's `import-worker` (the
// jail runs /proc/self/exe, as `roverplan serve` runs itself), so it answers that command too.
int main(int argc, char** argv) {
  if (argc >= 2 && std::string(argv[1]) == "import-worker")
    return rover::jail::importWorkerMain(std::vector<std::string>(argv + 2, argv + argc));
  return doctest::Context(argc, argv).run();
}
