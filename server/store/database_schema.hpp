#pragma once
// The server database's schema (maps, PDMs, missions, zones, history, counters) and its migrations, one version a
// step; the database's connection and rows are database.cpp's.
#include <string>

struct sqlite3;

namespace rover::store {

// Creates the schema in a new file, or migrates an older one to the current version, in one write
// transaction: two processes opening a fresh file at once cannot both initialise it. Throws
// std::runtime_error for a file of a newer schema version (StorageFull for a full disk).
void migrateSchema(sqlite3* db, const std::string& path);

}  // namespace rover::store
