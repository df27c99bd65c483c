// The compiled part of the Python module (`sidc._sidc`, pybind11): conversion between Python and
// sidc, and nothing else. python/sidc/__init__.py is the face users see; python/sessions.hpp does the work.
//
// Relies on: pybind11 and numpy's buffer protocol; sessions.hpp for fit, select and simulate;
// compiler/ for compiling a model; diagnostics/cli_catalogue.hpp for every message about keyword
// settings and arrays. Guarantees:
// - Every user error is a Python exception, never a crash: sidc's diagnostics raise
//   sidc.ModelError (str() is the text the CLI prints, with file, line, column, message, hint and
//   code as fields); a wrong keyword or a wrong type raises TypeError, a wrong value ValueError, with
//   the catalogue's wording.
// - A dict of 1-D arrays is the record a CSV with those column names would give (`t` or `time` is
//   the time column, as read_csv and bind_record take it). A contiguous, aligned float64 array is
//   not copied: the record borrows its memory (runtime/records/column.hpp) and holds a reference to
//   the array for as long as the fit keeps the record (the result's residuals() read it again), so
//   the array must not be changed meanwhile. A strided one is copied once; other float dtypes are
//   converted by numpy first (and the converted array borrowed); integer, bool, complex and object
//   arrays are refused. Binding, the fit window and the operators read the borrowed memory in
//   place; only `every`, `resample` or a held input's shift make new columns. A "row" in a message
//   about an array is its 0-based index, the "column" the 1-based position of its key.
// - Arrays handed back (residuals, simulated outputs) are the result's own memory, wrapped without
//   a copy.
// - The interpreter lock is released while sidc computes (the fit, its residuals, a selection, a
//   simulation): other Python threads run meanwhile.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fmt/format.h>

#include "compiler/load_model.hpp"
#include "compiler/pipeline.hpp"
#include "diagnostics/cli_catalogue.hpp"
#include "diagnostics/model_catalogue.hpp"
#include "ir/print.hpp"
#include "python/sessions.hpp"

namespace py = pybind11;
using namespace sidc;
using namespace sidc::python;

namespace {

// sidc's diagnostics on their way to sidc.ModelError (raised by the translator in the module init).
struct DiagnosticError {
  Failure diagnostics;
  std::string text;  // when there are no structured diagnostics (a compiled model file's error)
};

[[noreturn]] void raise(Failure diagnostics) { throw DiagnosticError{std::move(diagnostics), {}}; }
[[noreturn]] void type_error(const Diagnostic& d) { throw py::type_error(render(d)); }
[[noreturn]] void value_error(const Diagnostic& d) { throw py::value_error(render(d)); }

py::dict diagnostic_fields(const Diagnostic& d) {
  py::dict f;
  f["code"] = d.code;
  f["severity"] = d.severity == Severity::error ? "error" : d.severity == Severity::warning ? "warning" : "note";
  f["message"] = d.message;
  f["hint"] = d.hint.empty() ? py::object(py::none()) : py::object(py::str(d.hint));
  if (d.data_file) {
    f["file"] = *d.data_file, f["line"] = d.row, f["column"] = d.column;
  } else if (d.span.known()) {
    const auto p = d.span.start();
    f["file"] = d.span.file->name, f["line"] = p.line, f["column"] = p.column;
  } else {
    f["file"] = py::none(), f["line"] = py::none(), f["column"] = py::none();
  }
  f["text"] = render(d);
  return f;
}

std::vector<std::string> rendered(const Failure& diagnostics) {
  std::vector<std::string> out;
  for (const auto& d : diagnostics) out.push_back(render(d));
  return out;
}

// A vector handed to numpy without a copy: the array owns it through a capsule.
py::array_t<double> numpy_owning(std::vector<double>&& values) {
  auto* owned = new std::vector<double>(std::move(values));
  py::capsule owner(owned, [](void* p) { delete static_cast<std::vector<double>*>(p); });
  return py::array_t<double>({owned->size()}, {sizeof(double)}, owned->data(), owner);
}

std::string type_name(const py::handle& h) { return py::str(py::type::of(h).attr("__name__")).cast<std::string>(); }

// ---- records ---------------------------------------------------------------------------------

// What keeps an array's memory alive while a column borrows it: a reference to the array, given
// back under the interpreter lock (the last column may go while sidc computes without it).
std::shared_ptr<const void> reference_to(py::array array) {
  return std::shared_ptr<const void>(new py::object(std::move(array)), [](const void* held) {
    py::gil_scoped_acquire lock;
    delete static_cast<const py::object*>(held);
  });
}

// One column from an array: a contiguous float64 array borrowed where it lies (no copy), a
// strided one copied element by element, other float dtypes converted by numpy first (and the
// converted array borrowed).
Column column_values(const std::string& record, const std::string& name, const py::handle& value) {
  py::array array = py::isinstance<py::array>(value) ? py::reinterpret_borrow<py::array>(value) : py::array(py::module_::import("numpy").attr("asarray")(value));
  if (array.ndim() != 1) value_error(cli_diag::array_not_one_dimensional(record, name, static_cast<std::size_t>(array.ndim())));
  const char kind = array.dtype().kind();
  if (kind != 'f') type_error(cli_diag::array_not_float(record, name, py::str(array.dtype()).cast<std::string>()));
  if (!array.dtype().is(py::dtype::of<double>())) array = py::array_t<double, py::array::forcecast>::ensure(array);
  const auto n = static_cast<std::size_t>(array.shape(0));
  const auto stride = array.strides(0);
  const char* base = static_cast<const char*>(array.data());
  const bool aligned = reinterpret_cast<std::uintptr_t>(base) % alignof(double) == 0;
  if (aligned && (stride == static_cast<py::ssize_t>(sizeof(double)) || n < 2))
    return Column::borrowed({reinterpret_cast<const double*>(base), n}, reference_to(std::move(array)));
  std::vector<double> out(n);
  for (std::size_t i = 0; i < n; ++i) std::memcpy(&out[i], base + static_cast<py::ssize_t>(i) * stride, sizeof(double));
  return out;
}

Record record_from_arrays(const std::string& path, const py::dict& arrays) {
  Record r;
  r.path = path;
  r.line_jumps = {{0, 0}};  // row k is shown as k: the array index
  std::string first;
  for (const auto& [key, value] : arrays) {
    const std::string name = py::str(key).cast<std::string>();
    auto column = column_values(path, name, value);
    if (!r.columns.empty() && column.size() != r.rows()) value_error(cli_diag::array_lengths_differ(path, name, column.size(), first, r.rows()));
    if (r.columns.empty()) first = name;
    r.names.push_back(name);
    r.columns.push_back(std::move(column));
    r.first_faults.emplace_back();
  }
  if (r.columns.empty()) value_error(cli_diag::record_without_columns(path));
  return r;
}

RecordInput record_input(const py::handle& item, const std::string& name) {
  if (py::isinstance<py::str>(item)) return item.cast<std::string>();
  if (py::isinstance(item, py::module_::import("os").attr("PathLike"))) return py::str(py::module_::import("os").attr("fspath")(item)).cast<std::string>();
  if (py::isinstance<py::dict>(item)) return record_from_arrays(name, py::reinterpret_borrow<py::dict>(item));
  type_error(cli_diag::not_a_record(type_name(item)));
}

// None: the model's data statements; a path or a dict: one record; a list or tuple: several.
std::vector<RecordInput> record_inputs(const py::object& data) {
  std::vector<RecordInput> out;
  if (data.is_none()) return out;
  if (py::isinstance<py::list>(data) || py::isinstance<py::tuple>(data)) {
    if (py::len(data) == 0) type_error(cli_diag::not_a_record("an empty list (None reads the model's data statements)"));
    std::size_t k = 0;
    for (const auto& item : data) out.push_back(record_input(item, "<arrays " + std::to_string(++k) + ">"));
    return out;
  }
  out.push_back(record_input(data, "<arrays>"));
  return out;
}

// ---- keyword settings --------------------------------------------------------------------------

// The keyword settings of one function, checked against its names (did-you-mean for a slip).
class Keywords {
 public:
  Keywords(std::string function, const py::dict& given, std::vector<std::string> names) : function_(std::move(function)), names_(std::move(names)) {
    for (const auto& [key, value] : given) {
      std::string name = py::str(key).cast<std::string>();
      if (name == "from_") name = "from";  // `from` is a Python keyword
      if (std::find(names_.begin(), names_.end(), name) == names_.end()) {
        std::string all;
        for (const auto& n : names_) all += (all.empty() ? "" : ", ") + n;
        type_error(cli_diag::unknown_keyword(function_, name, diag::nearest(name, names_), all));
      }
      values_[name] = py::reinterpret_borrow<py::object>(value);
    }
  }
  const py::object* get(const std::string& name) const {
    auto it = values_.find(name);
    return it == values_.end() || it->second.is_none() ? nullptr : &it->second;
  }
  void number(const std::string& name, std::optional<double>& out, bool positive = false) const {
    if (auto* v = get(name)) {
      if (py::isinstance<py::bool_>(*v) || !(py::isinstance<py::float_>(*v) || py::isinstance<py::int_>(*v)))
        type_error(cli_diag::keyword_wrong_type(name, type_name(*v), "a number"));
      out = v->cast<double>();
      if (!std::isfinite(*out) || (positive && !(*out > 0)))
        value_error(cli_diag::keyword_wrong_type(name, fmt::format("{}", *out), positive ? "a positive number" : "a finite number"));
    }
  }
  template <class Int>
  void integer(const std::string& name, Int& out, long long least) const {
    if (auto* v = get(name)) {
      if (py::isinstance<py::bool_>(*v) || !py::isinstance<py::int_>(*v)) type_error(cli_diag::keyword_wrong_type(name, type_name(*v), "an integer"));
      const long long x = v->cast<long long>();
      if (x < least) value_error(cli_diag::keyword_wrong_type(name, std::to_string(x), fmt::format("an integer of at least {}", least)));
      out = static_cast<Int>(x);
    }
  }
  void flag(const std::string& name, bool& out) const {
    if (auto* v = get(name)) {
      if (!py::isinstance<py::bool_>(*v)) type_error(cli_diag::keyword_wrong_type(name, type_name(*v), "True or False"));
      out = v->cast<bool>();
    }
  }
  void text(const std::string& name, std::string& out, const std::vector<std::string>& choices = {}) const {
    if (auto* v = get(name)) {
      if (!py::isinstance<py::str>(*v)) type_error(cli_diag::keyword_wrong_type(name, type_name(*v), "a string"));
      out = v->cast<std::string>();
      if (!choices.empty() && std::find(choices.begin(), choices.end(), out) == choices.end()) {
        std::string all;
        for (const auto& c : choices) all += (all.empty() ? "" : ", ") + c;
        value_error(cli_diag::keyword_not_one_of(name, out, all));
      }
    }
  }
  void names(const std::string& name, std::vector<std::string>& out) const {
    if (auto* v = get(name)) {
      if (py::isinstance<py::str>(*v)) {
        out.push_back(v->cast<std::string>());
        return;
      }
      if (!py::isinstance<py::list>(*v) && !py::isinstance<py::tuple>(*v)) type_error(cli_diag::keyword_wrong_type(name, type_name(*v), "a name or a list of names"));
      for (const auto& item : *v) {
        if (!py::isinstance<py::str>(item)) type_error(cli_diag::keyword_wrong_type(name, "a list holding " + type_name(item), "a list of names"));
        out.push_back(item.cast<std::string>());
      }
    }
  }

 private:
  std::string function_;
  std::vector<std::string> names_;
  std::map<std::string, py::object> values_;
};

const std::vector<std::string> kRecordKeywords{"from", "to", "every", "step", "resample", "derivative", "second_derivative",
                                               "edges", "integration", "precision", "weights", "split_at_gaps", "keep_outliers"};

std::vector<std::string> with_record_keywords(std::vector<std::string> own) {
  own.insert(own.begin(), kRecordKeywords.begin(), kRecordKeywords.end());
  return own;
}

RecordSettings record_settings(const Keywords& k) {
  RecordSettings r;
  k.number("from", r.from);
  k.number("to", r.to);
  k.number("step", r.step, true);
  k.number("resample", r.resample, true);
  if (k.get("every")) {
    int every = 1;
    k.integer("every", every, 1);
    r.every = every;
  }
  k.text("derivative", r.derivative);
  k.text("second_derivative", r.second_derivative, {"repeated", "direct"});
  k.text("edges", r.edges, {"drop", "shorten"});
  k.text("integration", r.integration, {"simpson", "trapezoid"});
  k.text("precision", r.precision, {"automatic", "double", "extended"});
  k.text("weights", r.weights);
  k.flag("split_at_gaps", r.split_at_gaps);
  k.flag("keep_outliers", r.keep_outliers);
  r.keep_outliers_name = "keep_outliers=True";
  return r;
}

// ---- the model -----------------------------------------------------------------------------------

using ModelHandle = std::shared_ptr<LoadedModel>;  // never changed after compiling

py::tuple compiled(std::shared_ptr<const SourceFile> source, const std::string& directory) {
  CompileResult r = compile(source, {});
  if (!r.ok()) raise(r.diagnostics.items);
  auto model = std::make_shared<LoadedModel>(LoadedModel{compiled_model(source, *r.normalized, *r.integrated), source->name, directory});
  return py::make_tuple(ModelHandle(model), rendered(r.diagnostics.items));
}

py::tuple compile_text(const std::string& text, const std::string& name) {
  return compiled(std::make_shared<const SourceFile>(name, text), std::filesystem::current_path().string());
}

py::tuple compile_file(const std::string& path) {
  const std::string directory = std::filesystem::absolute(path).parent_path().string();
  if (path.ends_with(".sidc.json")) {
    std::string error, warnings;
    auto loaded = load_compiled_model(path, error, warnings);
    if (!loaded) throw DiagnosticError{{}, error};
    std::vector<std::string> said;
    if (!warnings.empty()) said.push_back(warnings.substr(0, warnings.size() - 1));
    return py::make_tuple(ModelHandle(std::make_shared<LoadedModel>(LoadedModel{std::move(*loaded), path, directory})), said);
  }
  auto text = read_text_file(path);
  if (auto* d = std::get_if<Diagnostic>(&text)) raise({cli_diag::model_not_read(*d)});
  return compiled(std::make_shared<const SourceFile>(path, std::get<std::string>(std::move(text))), directory);
}

py::dict signals(const ModelHandle& m) {
  py::dict out;
  for (const auto& s : m->compiled.normalized.signals) out[py::str(s.name)] = s.kind == ir::Signal::Kind::input ? "input" : "output";
  return out;
}

std::vector<std::string> parameters(const ModelHandle& m) {
  std::vector<std::string> out;
  for (const auto& p : m->compiled.normalized.parameters) out.push_back(p.name);
  return out;
}

// ---- fit, select, simulate ---------------------------------------------------------------------------

using FitHandle = std::shared_ptr<FitSession>;  // never changed after the fit

FitHandle run_fit(const ModelHandle& m, const py::object& data, const py::dict& kwargs) {
  const Keywords k("fit", kwargs, with_record_keywords({"integrate", "form", "no_validate", "validate", "validate_samples", "refine_samples", "refine_segments", "initial_state",
                                                         "refine", "no_noise_check", "estimator", "local", "stride", "forget"}));
  driver::FitSettings s;
  s.records = record_settings(k);
  std::string integrate, form, initial_state;
  if (auto* v = k.get("integrate")) integrate = py::str(*v).cast<std::string>();  // 0..8 or "auto", checked as --integrate is
  k.text("form", form, {"derivative", "integrated", "weak"});
  if (!form.empty() && !integrate.empty()) value_error(cli_diag::invalid_options("`form` and `integrate` exclude each other (as `--form` and `--integrate` do): give one of them"));
  k.flag("no_validate", s.no_validate);
  if (auto* v = k.get("validate")) s.validate = record_inputs(*v);
  k.integer("validate_samples", s.validate_samples, 0);
  k.integer("refine_samples", s.refine_samples, 0);
  k.integer("refine_segments", s.refine_segments, 0);
  k.text("initial_state", initial_state, {"estimate", "record"});
  if (initial_state == "record") s.initial_state = InitialState::record;
  k.flag("refine", s.refine);
  bool no_noise_check = false;
  k.flag("no_noise_check", no_noise_check);
  s.noise_check = !no_noise_check;
  k.text("estimator", s.estimator, {"least_squares", "iv"});
  k.number("local", s.local, true);
  k.integer("stride", s.stride, 1);
  k.number("forget", s.forget, true);
  if (s.forget && !(*s.forget < 1))
    value_error(cli_diag::keyword_wrong_type("forget", fmt::format("{}", *s.forget), "a number strictly between 0 and 1"));
  s.no_validate_name = "no_validate";
  auto records = record_inputs(data);
  auto request = driver::integration_request(integrate, form);  // as sidc fit reads --integrate and --form
  if (auto* d = std::get_if<Diagnostic>(&request)) raise({*d});
  s.form = std::get<std::optional<ir::IntegrationRequest>>(request);
  std::variant<std::unique_ptr<FitSession>, Failure> result;
  {
    py::gil_scoped_release unlocked;
    result = fit_session(*m, std::move(records), std::move(s));
  }
  if (auto* f = std::get_if<Failure>(&result)) raise(std::move(*f));
  return FitHandle(std::get<std::unique_ptr<FitSession>>(std::move(result)));
}

std::vector<std::string> save(const FitHandle& s, const std::string& out, const std::string& plots, const std::string& report) {
  std::variant<std::vector<std::string>, std::string> result;
  {
    py::gil_scoped_release unlocked;
    result = save_session(*s, out, plots, report);
  }
  if (auto* error = std::get_if<std::string>(&result)) throw DiagnosticError{{}, *error};
  return std::get<std::vector<std::string>>(std::move(result));
}

std::string fit_json_text(const FitHandle& s) {
  py::gil_scoped_release unlocked;
  return fit_json_document(*s).dump(1) + "\n";
}

// The covariance of every estimate (fit.json's parameters, group by group), block-diagonal: the
// groups share no parameter, and each is solved alone.
py::tuple covariance(const FitHandle& s) {
  std::vector<std::string> names;
  for (const auto& g : s->run.summary.groups)
    for (const auto& p : g.summary.parameters) names.push_back(p.name);
  const auto n = static_cast<py::ssize_t>(names.size());
  py::array_t<double> out({n, n});
  auto m = out.mutable_unchecked<2>();
  for (py::ssize_t i = 0; i < n; ++i)
    for (py::ssize_t j = 0; j < n; ++j) m(i, j) = 0.0;
  py::ssize_t at = 0;
  for (const auto& g : s->run.summary.groups) {
    const auto& c = g.summary.covariance;
    for (Eigen::Index i = 0; i < c.rows(); ++i)
      for (Eigen::Index j = 0; j < c.cols(); ++j) m(at + i, at + j) = c(i, j);
    at += static_cast<py::ssize_t>(g.summary.parameters.size());
  }
  return py::make_tuple(names, out);
}

py::dict residuals(const FitHandle& s) {
  std::variant<ResidualColumns, Diagnostic> result;
  {
    py::gil_scoped_release unlocked;
    result = residual_columns(*s);
  }
  if (auto* d = std::get_if<Diagnostic>(&result)) raise({*d});
  auto& c = std::get<ResidualColumns>(result);
  py::dict out;
  out["group"] = numpy_owning(std::move(c.group));
  out["equation"] = numpy_owning(std::move(c.equation));
  out["record"] = numpy_owning(std::move(c.record));
  out["t"] = numpy_owning(std::move(c.time));
  out["known"] = numpy_owning(std::move(c.known));
  out["fitted"] = numpy_owning(std::move(c.fitted));
  out["residual"] = numpy_owning(std::move(c.residual));
  return out;
}

// The local fits as local.csv's columns (None without them): t_center, each parameter and its
// standard error (NaN where a window has no estimate), G, n, rank (groups after the first with
// their number appended, as in local.csv), and `record` (an index) when there are several records.
py::object local_arrays(const FitHandle& s) {
  if (!s->run.local) return py::none();
  const LocalFitSummary& l = *s->run.local;
  py::dict out;
  std::vector<double> t, record;
  for (std::size_t r = 0; r < l.groups.front().records.size(); ++r) {
    const auto& fit = l.groups.front().records[r];
    t.insert(t.end(), fit.t_center.begin(), fit.t_center.end());
    record.insert(record.end(), fit.windows(), static_cast<double>(r));
  }
  if (l.groups.front().records.size() > 1) out["record"] = numpy_owning(std::move(record));
  out["t_center"] = numpy_owning(std::move(t));
  for (std::size_t g = 0; g < l.groups.size(); ++g) {
    const auto& group = l.groups[g];
    const std::size_t p = group.columns.size();
    for (std::size_t j = 0; j < p; ++j) {
      std::vector<double> x, se;
      for (const auto& fit : group.records)
        for (std::size_t k = 0; k < fit.windows(); ++k) x.push_back(fit.estimates[k * p + j]), se.push_back(fit.standard_errors[k * p + j]);
      out[py::str(group.columns[j])] = numpy_owning(std::move(x));
      out[py::str(group.columns[j] + "_se")] = numpy_owning(std::move(se));
    }
    std::vector<double> G, n, rank;
    for (const auto& fit : group.records) {
      G.insert(G.end(), fit.G.begin(), fit.G.end());
      n.insert(n.end(), fit.n.begin(), fit.n.end());
      rank.insert(rank.end(), fit.rank.begin(), fit.rank.end());
    }
    const std::string suffix = l.groups.size() > 1 ? fmt::format("_{}", g + 1) : "";
    out[py::str("G" + suffix)] = numpy_owning(std::move(G));
    out[py::str("n" + suffix)] = numpy_owning(std::move(n));
    out[py::str("rank" + suffix)] = numpy_owning(std::move(rank));
  }
  return out;
}

py::tuple run_select(const ModelHandle& m, const py::object& data, const py::dict& kwargs) {
  const Keywords k("select", kwargs, with_record_keywords({"method", "rule", "require", "drop", "group", "folds", "bootstrap", "seed", "max_size",
                                                            "simulate", "simulate_samples", "keep_drift"}));
  SelectSettings s;
  s.records = record_settings(k);
  k.text("method", s.method, {"automatic", "exact", "stlsq", "frols"});
  k.text("rule", s.rule, {"elbow", "aic", "bic", "cv"});
  k.names("require", s.required);
  k.names("drop", s.dropped);
  if (auto* v = k.get("group")) {
    if (!py::isinstance<py::dict>(*v)) type_error(cli_diag::keyword_wrong_type("group", type_name(*v), "a dict of name: [parameters]"));
    for (const auto& [name, members] : py::reinterpret_borrow<py::dict>(*v)) {
      std::vector<std::string> list;
      const Keywords one("select", py::dict(py::arg("group") = members), {"group"});
      one.names("group", list);
      s.groups.emplace_back(py::str(name).cast<std::string>(), std::move(list));
    }
  }
  k.integer("folds", s.folds, 0);
  k.integer("bootstrap", s.bootstrap, 0);
  k.integer("seed", s.seed, 0);
  k.integer("max_size", s.max_size, 0);
  k.flag("simulate", s.simulate);
  k.integer("simulate_samples", s.simulate_samples, 0);
  k.flag("keep_drift", s.keep_drift);
  auto records = record_inputs(data);
  std::variant<SelectResult, Failure> result;
  {
    py::gil_scoped_release unlocked;
    result = select_session(*m, std::move(records), s);
  }
  if (auto* f = std::get_if<Failure>(&result)) raise(std::move(*f));
  auto& r = std::get<SelectResult>(result);
  return py::make_tuple(r.document.dump(), r.report, r.warnings);
}

std::vector<double> values_of(const std::string& what, const py::handle& value) { return column_values("simulate", what, value).to_vector(); }

py::tuple run_simulate(const ModelHandle& m, const py::dict& params, const py::object& inputs, const py::object& t, const py::object& initial,
                       const py::dict& kwargs) {
  const Keywords k("simulate", kwargs, {"method", "stepper", "substeps", "tolerance"});
  SimulateRequest r;
  k.text("method", r.method, {"rk4", "adaptive"});
  k.text("stepper", r.stepper, {"dopri5", "cash_karp"});
  if (k.get("substeps")) {
    int n = 1;
    k.integer("substeps", n, 1);
    r.substeps = n;
  }
  k.number("tolerance", r.tolerance, true);
  // One number per name, checked as a keyword of that name is (the message names the parameter).
  auto number_of = [](const py::handle& name, const py::handle& value) {
    const std::string n = py::str(name).cast<std::string>();
    py::dict one;
    one[py::str(n)] = value;
    std::optional<double> v;
    Keywords("simulate", one, {n}).number(n, v);
    return std::pair{n, *v};
  };
  for (const auto& [name, value] : params) r.parameters.push_back(number_of(name, value));
  r.time = values_of("t", t);
  if (!inputs.is_none()) {
    if (!py::isinstance<py::dict>(inputs)) type_error(cli_diag::keyword_wrong_type("inputs", type_name(inputs), "a dict of 1-D arrays"));
    for (const auto& [name, value] : py::reinterpret_borrow<py::dict>(inputs)) {
      const std::string n = py::str(name).cast<std::string>();
      auto v = values_of(n, value);
      if (v.size() != r.time.size()) value_error(cli_diag::array_lengths_differ("simulate", n, v.size(), "t", r.time.size()));
      r.inputs[n] = std::move(v);
    }
  }
  if (!initial.is_none()) {
    if (!py::isinstance<py::dict>(initial)) type_error(cli_diag::keyword_wrong_type("initial", type_name(initial), "a dict such as {\"y\": 1, \"y'\": 0}"));
    for (const auto& [name, value] : py::reinterpret_borrow<py::dict>(initial)) r.initial.push_back(number_of(name, value));
  }
  std::variant<SimulationSummary, Failure> result;
  {
    py::gil_scoped_release unlocked;
    result = simulate_session(*m, std::move(r));
  }
  if (auto* f = std::get_if<Failure>(&result)) raise(std::move(*f));
  auto& summary = std::get<SimulationSummary>(result);
  py::dict out;
  out["t"] = numpy_owning(std::move(summary.time).release());
  for (std::size_t i = 0; i < summary.output_names.size(); ++i) out[py::str(summary.output_names[i])] = numpy_owning(std::move(summary.outputs[i]));
  const std::string stopped = summary.completed() ? std::string() : render(cli_diag::simulation_stopped(summary.message));
  return py::make_tuple(out, summary.brief_report(), stopped);
}

}  // namespace

PYBIND11_MODULE(_sidc, module) {
  module.doc() = "sidc's engine (the Python face is the `sidc` package: docs/python.md)";
  module.attr("version") = SIDC_VERSION;
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const DiagnosticError& e) {
      py::list fields;
      for (const auto& d : e.diagnostics) fields.append(diagnostic_fields(d));
      std::string text = e.text;
      for (const auto& d : e.diagnostics) text += (text.empty() ? "" : "\n") + render(d);
      py::object error = py::module_::import("sidc").attr("ModelError")(text, fields);
      PyErr_SetObject(error.get_type().ptr(), error.ptr());
    }
  });
  py::class_<LoadedModel, ModelHandle>(module, "_Model")
      .def_property_readonly("path", [](const ModelHandle& m) { return m->path; })
      .def_property_readonly("name", [](const ModelHandle& m) { return m->compiled.integrated.name; })
      .def_property_readonly("rewritten", [](const ModelHandle& m) { return print(m->compiled.integrated); })
      .def_property_readonly("normalized", [](const ModelHandle& m) { return print(m->compiled.normalized); })
      .def_property_readonly("parameters", &parameters)
      .def_property_readonly("signals", &signals);
  py::class_<FitSession, FitHandle>(module, "_Fit")
      .def("json", &fit_json_text)
      .def("report", [](const FitHandle& s) { return s->report; })
      .def_property_readonly("warnings", [](const FitHandle& s) { return s->warnings; })
      .def_property_readonly("usable", [](const FitHandle& s) { return s->run.summary.is_solution_usable(); })
      .def("covariance", &covariance)
      .def("save", &save, py::arg("out"), py::arg("plots"), py::arg("report"))
      .def("residuals", &residuals)
      .def("local", &local_arrays);
  module.def("compile_text", &compile_text, py::arg("text"), py::arg("name"));
  module.def("compile_file", &compile_file, py::arg("path"));
  module.def("fit", &run_fit, py::arg("model"), py::arg("data"), py::arg("settings"));
  module.def("select", &run_select, py::arg("model"), py::arg("data"), py::arg("settings"));
  module.def("simulate", &run_simulate, py::arg("model"), py::arg("params"), py::arg("inputs"), py::arg("t"), py::arg("initial"), py::arg("settings"));
}
