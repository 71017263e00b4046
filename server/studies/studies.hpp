#pragma once
// The study engine (issue 12), as the CLI (`roverplan study`, `roverplan sweep`) and the server
// use it. A study is many seeded runs of one planner family over a grid of its parameters, worlds
// and team sizes; its results live in one SQLite database.
//
//   #include "server/studies/studies.hpp"
//   using namespace rover::studies;
//
//   StudySpec spec = parseStudySpec(body);      // throws rover::Error, field() = JSON path
//   StudySpec spec = presetSpec("laine-fig6", 100);  // or a preset (presetSpecJson for its JSON)
//
//   StudyDb db = StudyDb::open(path);           // created, or reopened to resume
//   StudyRunner runner(spec);                   // loads the maps once; throws rover::Error
//   CancelToken cancel;                         // DELETE: cancel.cancel()
//   RunOptions o;  o.threads = 1;  o.cancel = &cancel;  o.commitSeconds = 1;
//   RunReport r = runner.run(db, o, [](std::size_t done, std::size_t total) { /* WS frame */ });
//   // r.cancelled: stopped early; rerun run() later (e.g. after a server restart) to resume:
//   // only the runs not yet in the database are run.
//
//   db.summary()   -> StudySummary (toJson() for the API), the table `study summary` prints
//   db.runsCsv()   -> runs.csv;  the file at `path` is the downloadable study.sqlite
//   db.specJson()  -> the spec as stored;  db.runCount() -> runs done
//
// The progress callback runs on run()'s calling thread right after a commit, so it may read
// db.summary() for a partial summary (cost: one pass over the runs table).
// Threading: StudyRunner::run blocks its caller; the caller's thread is the only one touching the
// StudyDb (commits, progress callback), the workers only run planners. A server should run it on
// a thread of its own, with o.threads = the share of cores it grants studies, and may read the
// same file through a second StudyDb::open (SQLite WAL: readers do not block the writer).
// Execution modes with identical per-run rows: threads (RunOptions::threads), job-array shards
// (RunOptions::shardIndex/shardCount + StudyDb::mergeFrom) and MPI ranks (study_mpi.hpp).
#include "server/studies/study_db.hpp"
#include "server/studies/study_mpi.hpp"
#include "server/studies/study_runner.hpp"
#include "server/studies/study_spec.hpp"
