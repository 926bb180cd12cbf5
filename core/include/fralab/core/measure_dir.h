// The files of a measurement folder (`fralab measure --out DIR`, docs/formats.md §23), named in one
// place: every stage that writes or reads a run's files asks MeasureDir for the path.
#pragma once

#include <string>

#include "fralab/core/frd.h"

namespace fralab {

struct MeasureDir {
  std::string root;  // DIR

  explicit MeasureDir(std::string dir) : root(std::move(dir)) {}

  std::string frd_dir() const { return root + "/frd"; }
  /// DIR/frd/<E1>_<E2>.json: the curve of pair "E1:E2" (docs/formats.md §4).
  std::string frd(const std::string& pair) const {
    return frd_dir() + "/" + pair_file_stem(pair) + ".json";
  }
  std::string tf_dir() const { return root + "/tf"; }
  /// DIR/tf/<E1>_<E2>.json: the pair's fit (docs/formats.md §9).
  std::string tf(const std::string& pair) const {
    return tf_dir() + "/" + pair_file_stem(pair) + ".json";
  }
  std::string tape() const { return root + "/tape.lcmlog"; }
  std::string run_json() const { return root + "/run.json"; }
  std::string engine() const { return root + "/engine.json"; }
  std::string acquire_summary() const { return root + "/acquire.json"; }
  std::string transfer_matrix_json() const { return root + "/transfer_matrix.json"; }
  std::string transfer_matrix_md() const { return root + "/transfer_matrix.md"; }
  std::string logs_dir() const { return root + "/logs"; }
  /// DIR/logs/<process>.log: what a process of the run printed.
  std::string log(const std::string& process) const { return logs_dir() + "/" + process + ".log"; }
  /// DIR/validation: the validation measurement of `fralab diagnose --engine`, laid out the same.
  MeasureDir validation() const { return MeasureDir(root + "/validation"); }
  /// The auto campaign's two runs.
  MeasureDir multisine() const { return MeasureDir(root + "/multisine"); }
  MeasureDir sine() const { return MeasureDir(root + "/sine"); }
};

}  // namespace fralab
