#include "report/model_export.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <map>
#include <fmt/format.h>
#include <optional>
#include <set>

#include "diagnostics/cli_catalogue.hpp"
#include "ir/differentiate.hpp"

namespace sidc {
namespace {

using ir::FactorKind;

// A number as a floating literal both C and Python read as a double: shortest round trip, with a
// decimal point or an exponent so that C never reads it as an integer.
std::string literal(double v) {
  std::string s = fmt::format("{}", v);
  if (s.find_first_of(".eEn") == std::string::npos) s += ".0";  // `n`: nan, inf are refused before
  return s;
}

// A parameter's name as an identifier of the target language (`c1[1]` -> `c1_1`).
std::string identifier(const std::string& name, ExportLanguage language) {
  static const std::set<std::string> reserved{
      // C
      "auto", "break", "case", "char", "const", "continue", "default", "do", "double", "else", "enum", "extern", "float", "for",
      "goto", "if", "inline", "int", "long", "register", "restrict", "return", "short", "signed", "sizeof", "static", "struct",
      "switch", "typedef", "union", "unsigned", "void", "volatile", "while", "pow", "fabs", "sin", "cos", "exp", "log", "sqrt", "tanh",
      // Python
      "and", "as", "assert", "class", "def", "del", "elif", "except", "finally", "from", "global", "import", "in", "is", "lambda",
      "nonlocal", "not", "or", "pass", "raise", "try", "with", "yield", "None", "True", "False", "math", "abs",
      // the generated code's own names
      "t", "state", "inputs", "dstate", "rhs"};
  std::string out;
  for (char ch : name) out += std::isalnum(static_cast<unsigned char>(ch)) || ch == '_' ? ch : '_';
  while (!out.empty() && out.back() == '_') out.pop_back();
  if (reserved.count(out)) out += "_";
  (void)language;
  return out;
}

// The quantities of a model that only a record defines: code outside sidc has no record.
std::optional<std::string> record_only(const ir::Factor& f) {
  switch (f.kind) {
    case FactorKind::initial_value: return fmt::format("the initial value `{}(...)` (a number read from the record)", f.name);
    case FactorKind::window_start: return std::string("t0 (the start of the fit window)");
    case FactorKind::elapsed: return std::string("tau (the time since the start of the fit window)");
    case FactorKind::derivative: return std::string("der() (a derivative estimated from the record)");
    case FactorKind::integral: return std::string("int() (an integral over the record)");
    case FactorKind::test_function: return std::string("a weak-form test function");
    default: return std::nullopt;
  }
}

class CodePrinter {
 public:
  CodePrinter(const ir::Model& model, const ExplicitForm& form, ExportLanguage language) : model_(model), language_(language) {
    std::size_t offset = 0;
    for (const auto& o : form.outputs) {
      offsets_[o.name] = offset;
      orders_[o.name] = o.order;
      offset += static_cast<std::size_t>(o.order);
    }
  }

  // The recorded inputs (and derivative orders) met while printing, in order of first use.
  const std::vector<std::pair<std::string, int>>& inputs() const { return inputs_; }
  const std::optional<std::string>& problem() const { return problem_; }
  bool uses_sign() const { return uses_sign_; }

  std::string sum(const ir::Sum& s) {
    if (s.empty()) return "0.0";
    std::string out;
    for (const auto& t : s.terms) {
      const bool negative = t.coefficient.is_negative();
      std::string body = term(t, negative);
      if (out.empty()) out = negative ? "-" + body : body;
      else out += (negative ? " - " : " + ") + body;
    }
    return out;
  }

  // A sum as an operand of `*`, `/` or a power: parenthesised unless it is one plain factor.
  std::string operand(const ir::Sum& s) {
    const std::string text = sum(s);
    const bool simple = s.terms.size() == 1 && !s.terms.front().coefficient.is_negative() &&
                        (s.terms.front().factors.empty() ||
                         (s.terms.front().coefficient.is_one() && s.terms.front().factors.size() == 1 && s.terms.front().factors.front().second == 1));
    return simple ? text : "(" + text + ")";
  }

 private:
  bool python() const { return language_ == ExportLanguage::python; }

  std::string term(const ir::Term& t, bool drop_sign) {
    const Number c = drop_sign ? t.coefficient.abs() : t.coefficient;
    std::vector<std::string> parts;
    if (!c.is_one() || t.factors.empty()) parts.push_back(literal(c.value()));
    for (const auto& [f, power] : t.factors) {
      const std::string base = factor(f);
      if (power == 1) parts.push_back(base);
      else if (python()) parts.push_back(fmt::format("{}**{}", base, power < 0 ? fmt::format("({})", power) : std::to_string(power)));
      else parts.push_back(fmt::format("pow({}, {})", base, power));
    }
    std::string out;
    for (const auto& p : parts) out += (out.empty() ? "" : "*") + p;
    return out;
  }

  std::string factor(const ir::Factor& f) {
    if (auto why = record_only(f)) {
      if (!problem_) problem_ = *why;
      return "0.0";
    }
    switch (f.kind) {
      case FactorKind::time: return "t";
      case FactorKind::signal: return signal(f.name, f.order);
      case FactorKind::function: return function(f.name, operand_argument(*f.argument));
      case FactorKind::power:
        return python() ? fmt::format("{}**({})", operand(*f.argument), literal(f.exponent.value()))
                        : fmt::format("pow({}, {})", sum(*f.argument), literal(f.exponent.value()));
      case FactorKind::guard: {
        std::string test;
        for (const auto& c : f.conditions) {
          const std::string one = fmt::format("({} {} {})", sum(*c.lhs), ir::to_string(c.relation), sum(*c.rhs));
          test += (test.empty() ? "" : python() ? " and " : " && ") + one;
        }
        return python() ? fmt::format("(1.0 if {} else 0.0)", test) : fmt::format("({} ? 1.0 : 0.0)", test);
      }
      case FactorKind::parameter: return identifier(f.name, language_);  // a nonlinear one (`sin(L*y)`), declared with the others
      default: return "0.0";  // record_only() took the others
    }
  }

  std::string operand_argument(const ir::Sum& s) { return sum(s); }

  std::string function(const std::string& name, const std::string& argument) {
    if (name == "sign") uses_sign_ = true;
    if (python()) {
      if (name == "abs") return fmt::format("abs({})", argument);
      if (name == "sign") return fmt::format("sidc_sign({})", argument);
      return fmt::format("math.{}({})", name, argument);
    }
    if (name == "abs") return fmt::format("fabs({})", argument);
    if (name == "sign") return fmt::format("sidc_sign({})", argument);
    return fmt::format("{}({})", name, argument);
  }

  std::string signal(const std::string& name, int order) {
    if (auto it = offsets_.find(name); it != offsets_.end()) return fmt::format("state[{}]", it->second + static_cast<std::size_t>(order));
    const ir::Signal* s = model_.signal(name);
    if (s && s->definition) {  // an input the model defines: written out, differentiated exactly
      auto d = order == 0 ? std::optional<ir::Sum>(*s->definition) : differentiate(*s->definition, order);
      if (d) return "(" + sum(*d) + ")";
    }
    const std::pair<std::string, int> key{name, order};
    auto it = std::find(inputs_.begin(), inputs_.end(), key);
    if (it == inputs_.end()) it = inputs_.insert(inputs_.end(), key);
    return fmt::format("inputs[{}]", it - inputs_.begin());
  }

  const ir::Model& model_;
  ExportLanguage language_;
  std::map<std::string, std::size_t> offsets_;
  std::map<std::string, int> orders_;
  std::vector<std::pair<std::string, int>> inputs_;
  std::optional<std::string> problem_;
  bool uses_sign_ = false;
};

std::string primed(const std::string& name, int order) { return name + std::string(static_cast<std::size_t>(order), '\''); }

// A ParametricSum with the values in: `m*(y') + ...`, parameters by name.
std::string parametric(CodePrinter& p, const ParametricSum& s, const ir::Model& model, ExportLanguage language) {
  std::string out = s.constant.empty() ? "" : p.sum(s.constant);
  for (const auto& t : s.terms) {
    const std::string name = identifier(model.parameters[static_cast<std::size_t>(t.parameter)].name, language);
    const auto one = t.operation.as_number();
    out += (out.empty() ? "" : " + ") + (one && one->is_one() ? name : name + "*" + p.operand(t.operation));
  }
  return out.empty() ? "0.0" : out;
}

std::string code(const ExportRequest& r, ExportLanguage language, std::string& problem) {
  const bool py = language == ExportLanguage::python;
  const std::string comment = py ? "#" : "//";
  const ExplicitForm& form = r.form;
  CodePrinter printer(r.normalized, form, language);
  const std::size_t k = form.outputs.size();
  const std::size_t n = form.state_size();
  // The bodies first: printing them finds the recorded inputs the header lists.
  std::vector<std::vector<std::string>> a(k, std::vector<std::string>(k));
  std::vector<std::string> rest(k);
  for (std::size_t i = 0; i < k; ++i) {
    for (std::size_t j = 0; j < k; ++j) a[i][j] = parametric(printer, form.coefficient[i][j], r.normalized, language);
    rest[i] = parametric(printer, form.rest[i], r.normalized, language);
  }
  if (printer.problem()) {
    problem = *printer.problem();
    return {};
  }
  std::string state_list, input_list;
  std::vector<std::size_t> highest;  // index in dstate of each output's highest derivative
  std::size_t offset = 0;
  for (const auto& o : form.outputs) {
    for (int m = 0; m < o.order; ++m) state_list += fmt::format("{}{}", state_list.empty() ? "" : ", ", primed(o.name, m));
    offset += static_cast<std::size_t>(o.order);
    highest.push_back(offset - 1);
  }
  for (const auto& [name, order] : printer.inputs()) input_list += fmt::format("{}{}", input_list.empty() ? "" : ", ", primed(name, order));
  if (input_list.empty()) input_list = "none (every input is defined in the model)";

  std::string out;
  out += fmt::format("{} Model `{}` with the fitted parameters of {}, written by sidc export.\n", comment, r.normalized.name, r.origin);
  out += fmt::format("{} The equations solved for the highest derivatives (the explicit form `sidc simulate` solves).\n", comment);
  out += fmt::format("{} state  ({} values): {}\n", comment, n, state_list);
  out += fmt::format("{} inputs ({} values): {}\n", comment, printer.inputs().size(), input_list);
  out += fmt::format("{} dstate: the time derivative of each state value.\n", comment);
  if (py) {
    out += "import math\n\n";
    for (std::size_t i = 0; i < r.normalized.parameters.size(); ++i)
      out += fmt::format("{} = {}\n", identifier(r.normalized.parameters[i].name, language), literal(r.values[i]));
    out += fmt::format("\nSTATE_SIZE = {}\nINPUT_SIZE = {}\n\n", n, printer.inputs().size());
    if (printer.uses_sign()) out += "def sidc_sign(x):\n    return (x > 0) - (x < 0)\n\n";
    out += "def rhs(t, state, inputs=()):\n";
    out += fmt::format("    dstate = [0.0] * {}\n", n);
    std::size_t at = 0;
    for (const auto& o : form.outputs) {
      for (int m = 0; m + 1 < o.order; ++m) out += fmt::format("    dstate[{}] = state[{}]\n", at + static_cast<std::size_t>(m), at + static_cast<std::size_t>(m) + 1);
      at += static_cast<std::size_t>(o.order);
    }
    out += "    # sum_j sidc_A[i][j] * (highest derivative of output j) + sidc_r[i] = 0, one row per equation\n";
    out += "    sidc_A = [";
    for (std::size_t i = 0; i < k; ++i) {
      out += (i ? ",\n         [" : "[");
      for (std::size_t j = 0; j < k; ++j) out += (j ? ", " : "") + a[i][j];
      out += "]";
    }
    out += "]\n    sidc_r = [";
    for (std::size_t i = 0; i < k; ++i) out += (i ? ",\n         " : "") + rest[i];
    out += "]\n";
    out += fmt::format(
        "    sidc_n = {0}\n"
        "    sidc_b = [-v for v in sidc_r]\n"
        "    for sidc_c in range(sidc_n):  # Gaussian elimination, partial pivoting\n"
        "        sidc_p = max(range(sidc_c, sidc_n), key=lambda sidc_row: abs(sidc_A[sidc_row][sidc_c]))\n"
        "        sidc_A[sidc_c], sidc_A[sidc_p] = sidc_A[sidc_p], sidc_A[sidc_c]\n"
        "        sidc_b[sidc_c], sidc_b[sidc_p] = sidc_b[sidc_p], sidc_b[sidc_c]\n"
        "        for sidc_row in range(sidc_c + 1, sidc_n):\n"
        "            sidc_f = sidc_A[sidc_row][sidc_c] / sidc_A[sidc_c][sidc_c]\n"
        "            for sidc_col in range(sidc_c, sidc_n):\n"
        "                sidc_A[sidc_row][sidc_col] -= sidc_f * sidc_A[sidc_c][sidc_col]\n"
        "            sidc_b[sidc_row] -= sidc_f * sidc_b[sidc_c]\n"
        "    sidc_x = [0.0] * sidc_n\n"
        "    for sidc_c in reversed(range(sidc_n)):\n"
        "        sidc_x[sidc_c] = (sidc_b[sidc_c] - sum(sidc_A[sidc_c][sidc_col] * sidc_x[sidc_col] for sidc_col in range(sidc_c + 1, sidc_n))) / sidc_A[sidc_c][sidc_c]\n",
        k);
    for (std::size_t j = 0; j < k; ++j) out += fmt::format("    dstate[{}] = sidc_x[{}]\n", highest[j], j);
    out += "    return dstate\n";
    return out;
  }
  out += "#include <math.h>\n\n";
  for (std::size_t i = 0; i < r.normalized.parameters.size(); ++i)
    out += fmt::format("static const double {} = {};\n", identifier(r.normalized.parameters[i].name, language), literal(r.values[i]));
  out += fmt::format("\nenum {{ SIDC_STATE_SIZE = {}, SIDC_INPUT_SIZE = {} }};\n\n", n, printer.inputs().size());
  if (printer.uses_sign()) out += "static double sidc_sign(double x) { return (x > 0) - (x < 0); }\n\n";
  out += "void sidc_rhs(double t, const double *state, const double *inputs, double *dstate) {\n";
  out += "  (void)t;\n  (void)inputs;\n";
  std::size_t at = 0;
  for (const auto& o : form.outputs) {
    for (int m = 0; m + 1 < o.order; ++m) out += fmt::format("  dstate[{}] = state[{}];\n", at + static_cast<std::size_t>(m), at + static_cast<std::size_t>(m) + 1);
    at += static_cast<std::size_t>(o.order);
  }
  out += "  /* sum_j sidc_A[i][j] * (highest derivative of output j) - sidc_b[i] = 0, one row per equation */\n";
  out += fmt::format("  double sidc_A[{0}][{0}], sidc_b[{0}], sidc_x[{0}];\n", k);
  for (std::size_t i = 0; i < k; ++i) {
    for (std::size_t j = 0; j < k; ++j) out += fmt::format("  sidc_A[{}][{}] = {};\n", i, j, a[i][j]);
    out += fmt::format("  sidc_b[{}] = -({});\n", i, rest[i]);
  }
  out += fmt::format(
      "  for (int sidc_c = 0; sidc_c < {0}; ++sidc_c) {{ /* Gaussian elimination, partial pivoting */\n"
      "    int sidc_p = sidc_c;\n"
      "    for (int sidc_row = sidc_c + 1; sidc_row < {0}; ++sidc_row)\n"
      "      if (fabs(sidc_A[sidc_row][sidc_c]) > fabs(sidc_A[sidc_p][sidc_c])) sidc_p = sidc_row;\n"
      "    for (int sidc_col = 0; sidc_col < {0}; ++sidc_col) {{ double sidc_s = sidc_A[sidc_c][sidc_col]; sidc_A[sidc_c][sidc_col] = sidc_A[sidc_p][sidc_col]; sidc_A[sidc_p][sidc_col] = sidc_s; }}\n"
      "    {{ double sidc_s = sidc_b[sidc_c]; sidc_b[sidc_c] = sidc_b[sidc_p]; sidc_b[sidc_p] = sidc_s; }}\n"
      "    for (int sidc_row = sidc_c + 1; sidc_row < {0}; ++sidc_row) {{\n"
      "      double sidc_f = sidc_A[sidc_row][sidc_c] / sidc_A[sidc_c][sidc_c];\n"
      "      for (int sidc_col = sidc_c; sidc_col < {0}; ++sidc_col) sidc_A[sidc_row][sidc_col] -= sidc_f * sidc_A[sidc_c][sidc_col];\n"
      "      sidc_b[sidc_row] -= sidc_f * sidc_b[sidc_c];\n"
      "    }}\n"
      "  }}\n"
      "  for (int sidc_c = {0} - 1; sidc_c >= 0; --sidc_c) {{\n"
      "    double sidc_s = sidc_b[sidc_c];\n"
      "    for (int sidc_col = sidc_c + 1; sidc_col < {0}; ++sidc_col) sidc_s -= sidc_A[sidc_c][sidc_col] * sidc_x[sidc_col];\n"
      "    sidc_x[sidc_c] = sidc_s / sidc_A[sidc_c][sidc_c];\n"
      "  }}\n",
      k);
  for (std::size_t j = 0; j < k; ++j) out += fmt::format("  dstate[{}] = sidc_x[{}];\n", highest[j], j);
  out += "}\n";
  return out;
}

// ---- LaTeX --------------------------------------------------------------------------------------

class LatexPrinter {
 public:
  std::string sum(const ir::Sum& s) {
    if (s.empty()) return "0";
    std::string out;
    for (const auto& t : s.terms) {
      const bool negative = t.coefficient.is_negative();
      const std::string body = term(t, negative ? -t.coefficient : t.coefficient);
      out += out.empty() ? (negative ? "-" : "") + body : (negative ? " - " : " + ") + body;
    }
    return out;
  }
  std::string operand(const ir::Sum& s) {
    const std::string text = sum(s);
    return s.terms.size() == 1 && !s.terms.front().coefficient.is_negative() ? text : "\\left(" + text + "\\right)";
  }
  // value * operation, the value first.
  std::string scaled(double value, const ir::Sum& operation) {
    const bool plain_number = operation.terms.size() == 1 && operation.terms.front().factors.empty();
    if (plain_number) return number(value * operation.terms.front().coefficient.value());
    return number(value) + "\\," + operand(operation);
  }

  static std::string number(double v) {
    std::string s = fmt::format("{:.6g}", v);
    const auto e = s.find('e');
    if (e == std::string::npos) return s;
    const int exponent = std::stoi(s.substr(e + 1));
    return fmt::format("{} \\times 10^{{{}}}", s.substr(0, e), exponent);
  }

  static std::string name(const std::string& n) {
    static const std::set<std::string> greek{"alpha", "beta", "gamma", "delta", "epsilon", "zeta", "eta", "theta", "iota", "kappa",
                                             "mu", "nu", "xi", "pi", "rho", "sigma", "tau", "upsilon", "phi", "chi", "psi", "omega",
                                             "Gamma", "Delta", "Theta", "Lambda", "Xi", "Pi", "Sigma", "Phi", "Psi", "Omega"};
    if (n.size() == 1) return n;
    if (greek.count(n)) return "\\" + n;
    std::string escaped;
    for (char c : n) escaped += c == '_' ? std::string("\\_") : std::string(1, c);
    return "\\mathit{" + escaped + "}";
  }

 private:
  std::string term(const ir::Term& t, const Number& c) {
    std::string out = c.is_one() && !t.factors.empty() ? "" : number(c.value());
    for (const auto& [f, power] : t.factors) {
      std::string base = factor(f);
      if (power != 1) base = (f.kind == FactorKind::signal && f.order > 0 ? "\\left(" + base + "\\right)" : base) + fmt::format("^{{{}}}", power);
      out += (out.empty() ? "" : "\\,") + base;
    }
    return out;
  }

  std::string factor(const ir::Factor& f) {
    switch (f.kind) {
      case FactorKind::time: return "t";
      case FactorKind::elapsed: return "\\tau";
      case FactorKind::window_start: return "t_0";
      case FactorKind::signal: {
        const std::string n = name(f.name);
        if (f.order == 0) return n;
        if (f.order == 1) return "\\dot{" + n + "}";
        if (f.order == 2) return "\\ddot{" + n + "}";
        return fmt::format("{}^{{({})}}", n, f.order);
      }
      case FactorKind::initial_value: return fmt::format("{}({})", name(f.name), f.at ? number(f.at->value()) : "t_0");
      case FactorKind::function:
        if (f.name == "abs") return "\\left|" + sum(*f.argument) + "\\right|";
        if (f.name == "sqrt") return "\\sqrt{" + sum(*f.argument) + "}";
        if (f.name == "sign") return "\\operatorname{sign}\\left(" + sum(*f.argument) + "\\right)";
        return "\\" + f.name + "\\left(" + sum(*f.argument) + "\\right)";
      case FactorKind::power: return operand(*f.argument) + "^{" + number(f.exponent.value()) + "}";
      case FactorKind::integral: return "\\int_{t_0}^{t} " + operand(*f.argument) + "\\,dt";
      case FactorKind::derivative: return fmt::format("\\frac{{d^{{{0}}}}}{{dt^{{{0}}}}}", f.order) + operand(*f.argument);
      case FactorKind::guard: {
        static const char* relations[] = {"<", "\\le", ">", "\\ge"};
        std::string out;
        for (const auto& c : f.conditions)
          out += (out.empty() ? "" : " \\wedge ") + sum(*c.lhs) + " " + relations[static_cast<int>(c.relation)] + " " + sum(*c.rhs);
        return "\\left[" + out + "\\right]";
      }
      case FactorKind::test_function: return fmt::format("\\varphi_j^{{({})}}", f.order);
      case FactorKind::parameter: return name(f.name);
    }
    return {};
  }
};

std::string latex(const ExportRequest& r) {
  LatexPrinter p;
  const ir::Model& m = r.normalized;
  std::string out = fmt::format("% Model `{}` with the fitted parameters of {}, written by sidc export.\n", m.name, r.origin);
  out += "% The equations in their derivative form (sum_k a_k op_k = known, eq. 2-1.2), the numbers in place of a_k.\n";
  out += "% Needs amsmath.\n\\begin{align}\n";
  for (std::size_t i = 0; i < m.equations.size(); ++i) {
    const auto& e = m.equations[i];
    std::string lhs;
    for (const auto& t : e.terms) {
      const double v = r.values[static_cast<std::size_t>(t.parameter)];
      const std::string piece = p.scaled(std::abs(v), t.operation);
      lhs += lhs.empty() ? (v < 0 ? "-" : "") + piece : (v < 0 ? " - " : " + ") + piece;
    }
    out += fmt::format("  {} &= {}{}\n", lhs.empty() ? "0" : lhs, p.sum(e.known), i + 1 < m.equations.size() ? " \\\\" : "");
  }
  out += "\\end{align}\n\n\\begin{tabular}{lr}\n  parameter & estimate \\\\\n  \\hline\n";
  for (std::size_t i = 0; i < m.parameters.size(); ++i) {
    std::string escaped;
    for (char c : m.parameters[i].name) escaped += c == '_' ? std::string("\\_") : std::string(1, c);
    out += fmt::format("  \\texttt{{{}}} & ${}$ \\\\\n", escaped, LatexPrinter::number(r.values[i]));
  }
  out += "\\end{tabular}\n";
  return out;
}

}  // namespace

std::variant<std::string, Diagnostic> export_model(const ExportRequest& r, ExportLanguage language) {
  for (std::size_t i = 0; i < r.values.size(); ++i)
    if (!std::isfinite(r.values[i])) return cli_diag::cannot_export(fmt::format("the estimate of `{}` is not a finite number", r.normalized.parameters[i].name));
  if (language == ExportLanguage::latex) return latex(r);
  std::string problem;
  std::string text = code(r, language, problem);
  if (!problem.empty()) return cli_diag::cannot_export(fmt::format("the equations use {}, which code outside sidc has no value for", problem));
  return text;
}

}  // namespace sidc
