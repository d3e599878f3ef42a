// SPDX-License-Identifier: AGPL-3.0-or-later
// Writing the files beside an image: each to a temporary name in the same directory, renamed
// onto its own name once complete, so no file is ever left half-written. Failures are reported
// on stderr as "plenoptic camera: cannot write <what> <path>: <reason>".

#ifndef POVRAY_GLUE_OUTPUTS_FILES_H
#define POVRAY_GLUE_OUTPUTS_FILES_H

#include <cstdio>
#include <functional>
#include <string>

namespace plenoptic {

// `path` with its extension (if any) replaced by `suffix`: dir/name.ext -> dir/name<suffix>.
std::string replace_extension(const std::string& path, const std::string& suffix);

// The file's name without its directory (as the metadata names the files beside the image).
std::string base_name(const std::string& path);

// Writes `bytes` to `path`; `what` names the file in messages.
bool write_file_atomically(const char* what, const std::string& path, const std::string& bytes);
// The same, the bytes made piece by piece as they are written (memory: one piece): next(&piece)
// sets the next piece and returns true, or returns false when there is none left.
bool write_file_atomically(const char* what, const std::string& path,
                           const std::function<bool(std::string* piece)>& next);

// The general form: fill(file) writes the temporary file, which becomes `path` when it returns
// Fill::Complete. Fill::Failed reports the failure (with errno's reason); Fill::Abandoned
// (cancelled, or a source found wanting) removes the temporary file silently. Either way
// `path` is untouched and false is returned.
enum class Fill { Complete, Failed, Abandoned };
bool write_file_streamed(const char* what, const std::string& path, const std::function<Fill(std::FILE* file)>& fill);

// A scratch file for reading and writing in the directory of `path` (where the outputs have room),
// already removed from the directory, so it vanishes when closed or when the program ends;
// nullptr (errno set) when it cannot be made.
std::FILE* scratch_file_beside(const std::string& path);

// Writes a W x H one-channel float EXR (channel `channel`) row by row (memory: one row):
// fill(j, row) fills row j and returns false to stop (cancelled: nothing is written, no
// message). `what` names the file in messages.
bool write_float_exr(const std::string& path, const char* what, const char* channel, int W, int H,
                     const std::function<bool(int j, float* row)>& fill);

} // namespace plenoptic

#endif
