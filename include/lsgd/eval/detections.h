// Loop detections made by another system (or an earlier `lsgd run`), read
// from a CSV file so they can be scored with the same evaluate() code.
//
// Accepted files (blank lines and lines starting with '#' are skipped; fields
// are separated by commas, or by white space on lines without a comma;
// double-quoted fields may hold commas, quotes ("") and line breaks):
//   query,match,score[,...]   one row per query frame; match -1 = no loop
//                             (its score may then be empty); further columns
//                             are ignored; the header line is optional and,
//                             when present, may name the columns in any order
//                             (query or frame, match, score)
//   query,match,score,rank    top-k (lsgd match): up to k rows per query, its
//                             candidates by rank; rank 1 is the reported match
//                             (a header naming `rank` is required), so R@N
//                             counts a true match among the N best
//   lsgd run's CSV            frame,image,loop_frame,candidate_frame,score,ms:
//                             recognised by its header; candidate_frame is the
//                             match (the reported candidate whatever its score,
//                             so the threshold sweep sees every report) and ms
//                             the per-frame time; with ranked_frame,
//                             ranked_score and ranked_confirmed (written since
//                             the ranking was), R@100P and AP sweep the ranking
//                             (FrameRecord::ranking), as lsgd eval does
// Frame ids are 0-based and must be those of the evaluated sequence (after
// any --first/--last/--every).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "lsgd/eval/metrics.h"

namespace lsgd::eval {

// Reads `path` and returns one record per query that has a row, in frame
// order (evaluate() counts every other frame of the ground truth as a query
// that reported nothing); a row with match -1 reports no loop. Memory grows
// with the rows, not with the frame ids. A reported match is
// also the record's only candidate, so Recall@1/5/10 of detections read from
// a file are all the recall of the reported match, unless the file ranks
// several candidates per query (a rank column). frames = -1 takes the
// largest query + 1. Throws IoError when the file cannot be read, and
// FormatError naming file:line for a malformed row, a non-integer id, a
// non-finite score, a query outside [0, frames), a match outside
// [-1, frames), a query given twice (a query and rank, in a top-k file; a
// query without rank 1), or a file with no row.
std::vector<FrameRecord> read_detections(const std::string& path, std::int64_t frames = -1);

// What a reader of detections `records` (read from the file called `name`)
// scored against `gt` with window `min_gap` should be told, empty when all is
// well: revisits the ground truth lists that have no row (they count as
// missed: a CSV of `lsgd run --every 2` scored without --every 2), and
// reported matches that are the query itself or a later frame (a loop closes
// on an earlier frame; the strict protocol counts them as false loops: a
// system that stores a frame before it queries it, or columns given as
// match,query). `lsgd eval --detections` prints, stores and shows them;
// Python's evaluate_detections() raises them as warnings.
std::vector<std::string> detections_warnings(const std::vector<FrameRecord>& records,
                                             const GroundTruth& gt, std::int64_t min_gap,
                                             const std::string& name);

}  // namespace lsgd::eval
