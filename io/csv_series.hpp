// CSV time series in the output folder: one file per diagnostic, a header row, then rows.
#pragma once

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <string>
#include <vector>

#include "core/error.hpp"

namespace sphdem {

class CsvSeries {
 public:
  CsvSeries() = default;
  CsvSeries(const std::string& path, const std::vector<std::string>& columns, bool append = false,
            double keep_before = INFINITY) {
    open(path, columns, append, keep_before);
  }
  CsvSeries(const CsvSeries&) = delete;
  CsvSeries& operator=(const CsvSeries&) = delete;
  CsvSeries(CsvSeries&& o) noexcept : f_(o.f_), path_(std::move(o.path_)) { o.f_ = nullptr; }
  ~CsvSeries() {
    if (f_) std::fclose(f_);
  }

  // append: continue an existing series (restart); the header is written only to a new file.
  // Rows from t = keep_before on (written after the checkpoint a restart starts from) are dropped
  // first, so a restarted run does not repeat them.
  void open(const std::string& path, const std::vector<std::string>& columns, bool append = false,
            double keep_before = INFINITY) {
    bool fresh = true;
    if (append) check_header(path, columns);
    if (append && std::isfinite(keep_before)) trim(path, keep_before);
    if (append) {
      if (std::FILE* probe = std::fopen(path.c_str(), "r")) {
        fresh = std::fgetc(probe) == EOF;
        std::fclose(probe);
      }
    }
    f_ = std::fopen(path.c_str(), append ? "a" : "w");
    if (!f_) throw InputError("cannot write output file '" + path + "'");
    path_ = path;
    if (!fresh) return;
    for (std::size_t i = 0; i < columns.size(); ++i)
      std::fprintf(f_, "%s%s", i ? "," : "", columns[i].c_str());
    std::fprintf(f_, "\n");
  }
  void row(const std::vector<double>& values) {
    for (std::size_t i = 0; i < values.size(); ++i)
      std::fprintf(f_, "%s%.10g", i ? "," : "", values[i]);
    std::fprintf(f_, "\n");
    std::fflush(f_);
  }
  const std::string& path() const { return path_; }

  // A series to be continued must have this run's columns: rows of another width under its
  // header would be misread. A file that is not there, or is empty, passes.
  static void check_header(const std::string& path, const std::vector<std::string>& columns) {
    std::ifstream in(path);
    std::string have, want;
    if (!in || !std::getline(in, have)) return;
    for (std::size_t i = 0; i < columns.size(); ++i) want += (i ? "," : "") + columns[i];
    if (have != want)
      throw InputError(path + ": its columns (" + have + ") are not this run's (" + want +
                       "): it was written by another scene or an earlier sphdem; move it away "
                       "to restart into this folder");
  }

  // Keeps the header and the rows whose first value is below t (a file that is not there stays
  // so). A row printed at t itself (10 digits) may read back a little below it: it is dropped.
  static void trim(const std::string& path, double t) {
    std::ifstream in(path);
    if (!in) return;
    std::string line, kept;
    bool header = true;
    while (std::getline(in, line)) {
      if (header || std::strtod(line.c_str(), nullptr) < t - 1e-9 * std::fabs(t))
        kept += line + "\n";
      header = false;
    }
    in.close();
    std::FILE* out = std::fopen(path.c_str(), "w");
    if (!out) throw InputError("cannot write output file '" + path + "'");
    std::fputs(kept.c_str(), out);
    std::fclose(out);
  }

 private:
  std::FILE* f_ = nullptr;
  std::string path_;
};

}  // namespace sphdem
