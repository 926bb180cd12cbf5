// A MATLAB/Octave .mat (level 5) file through matio: the values fralab writes (real and complex
// matrices, text, lists of text, structs of named values) and the real vectors it reads. Files
// load with Octave's and MATLAB's `load` and Python's scipy.io.loadmat.
#pragma once

#include <complex>
#include <memory>
#include <string>
#include <vector>

namespace fralab {

/// One value: a real matrix (column-major, rows x cols), a complex one, a char row, a cell row of
/// char rows, or a struct whose fields are values (in insertion order).
struct MatValue {
  enum class Kind { kReal, kComplex, kText, kTextList, kStruct };
  Kind kind = Kind::kReal;
  size_t rows = 0, cols = 0;
  std::vector<double> real;
  std::vector<std::complex<double>> complex;
  std::string text;
  std::vector<std::string> texts;
  // A struct's fields: names and values side by side (a std::pair of the incomplete MatValue is
  // not allowed in the class; a std::vector of it is).
  std::vector<std::string> field_names;
  std::vector<MatValue> field_values;

  // (Defined out of line: the class must be complete before a MatValue is made or destroyed.)
  static MatValue scalar(double v);
  static MatValue column(const std::vector<double>& v);
  static MatValue matrix(size_t rows, size_t cols, std::vector<double> v);
  static MatValue complex_column(const std::vector<std::complex<double>>& v);
  static MatValue str(const std::string& s);
  static MatValue str_list(const std::vector<std::string>& s);
  static MatValue structure();
  MatValue& add(const std::string& name, MatValue v);  // a struct's field; returns it
};

/// A MATLAB name: a letter, then letters, digits, underscores, at most 63 characters.
bool is_mat_name(const std::string& name);

/// Writes the variables (each name is_mat_name) to `path` (level 5, compressed). InputError naming
/// the file or variable on failure.
void write_mat_file(const std::string& path,
                    const std::vector<std::pair<std::string, MatValue>>& variables);

/// The real numeric vectors (rows x 1 or 1 x rows, any numeric class, converted to double) of a
/// .mat file, by name in file order; other variables are listed in *skipped. InputError naming
/// the file when it is not a .mat file matio can read.
std::vector<std::pair<std::string, std::vector<double>>> read_mat_vectors(
    const std::string& path, std::vector<std::string>* skipped);

}  // namespace fralab
