#pragma once
// `roverplan import-worker IN OUT`: the process a client's raster is parsed in (import_jail.hpp).
// Reads OUT/request.json, opens the files of IN through GDAL under maps::UploadSandbox (the driver
// allow-list and the file checks hold inside the jail too), and writes OUT/result.json +
// OUT/grid.f32, or OUT/error.json with the client's answer. Exit status 0 (result), 1 (error
// written), 2 (misuse). `import-worker --probe` exits 0: the jail's start-up check that the
// binary runs inside it.
#include <string>
#include <vector>

namespace rover::jail {

int importWorkerMain(const std::vector<std::string>& args);

}  // namespace rover::jail
