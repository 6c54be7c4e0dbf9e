// CSV time series in the output folder: one file per diagnostic, a header row, then rows.
#pragma once

#include <cstdio>
#include <string>
#include <vector>

#include "core/error.hpp"

namespace sphdem {

class CsvSeries {
 public:
  CsvSeries() = default;
  CsvSeries(const std::string& path, const std::vector<std::string>& columns, bool append = false) {
    open(path, columns, append);
  }
  CsvSeries(const CsvSeries&) = delete;
  CsvSeries& operator=(const CsvSeries&) = delete;
  CsvSeries(CsvSeries&& o) noexcept : f_(o.f_), path_(std::move(o.path_)) { o.f_ = nullptr; }
  ~CsvSeries() {
    if (f_) std::fclose(f_);
  }

  // append: continue an existing series (restart); the header is written only to a new file.
  void open(const std::string& path, const std::vector<std::string>& columns, bool append = false) {
    bool fresh = true;
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

 private:
  std::FILE* f_ = nullptr;
  std::string path_;
};

}  // namespace sphdem
