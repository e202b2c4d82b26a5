//! Weight expressions: the formulas in which a scheme file writes its masks, such as
//! `"(k - 2) / k"` or `"(1/4 + cos(2*pi*j/k) + cos(4*pi*j/k)/2) / k"`.
//!
//! Grammar: numbers, the variables `k` (the valence of a vertex, or the size of a face; `n` is
//! the same variable) and `j` (the index of a neighbour, from 0), the constant `pi`, `+ - * / ^`,
//! parentheses, and the functions `cos`, `sin`, `sqrt`, `abs`.

use std::fmt;

use serde::{Deserialize, Deserializer, Serialize, Serializer};

/// A parsed weight formula. Grammar: numbers, the variables `k` (the valence of a vertex, or
/// the size of a face; `n` is the same variable) and `j` (the index of a neighbour, from 0), the
/// constant `pi`, `+ - * / ^`, parentheses, and the functions `cos`, `sin`, `sqrt`, `abs`.
///
/// ```
/// use subdiv_schemes::Expr;
///
/// let beta: Expr = "(5/8 - (3/8 + cos(2*pi/k)/4)^2) / k".parse()?;
/// assert!((beta.eval(6, 0) - 1.0 / 16.0).abs() < 1e-15);
/// # Ok::<(), subdiv_schemes::ExprError>(())
/// ```
#[derive(Clone, Debug)]
pub struct Expr {
    source: String,
    root: Node,
}

/// The deepest nesting a weight formula may have: parentheses, unary minus signs, powers and
/// function calls, each one level. The parser descends once per level, so this bounds its stack;
/// the masks of the built-in schemes nest at most 4 levels.
pub const MAX_FORMULA_DEPTH: usize = 256;

/// The longest weight formula, in bytes. Chains such as `1 + 1 + …` make trees as deep as they
/// are long, which evaluation walks recursively, so the length bounds that stack too.
pub const MAX_FORMULA_LENGTH: usize = 4096;

/// Why a weight formula does not parse.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("in `{formula}` at column {column}: {message}")]
pub struct ExprError {
    /// The formula, or for a long one the 60 bytes or so around the column, with `…`
    /// where it was cut (so that the message stays one short line).
    pub formula: String,
    /// 1-based column of the problem.
    pub column: usize,
    /// What is wrong.
    pub message: String,
}

#[derive(Clone, Debug)]
enum Node {
    Number(f64),
    Size,
    Index,
    Neg(Box<Node>),
    Binary(Op, Box<Node>, Box<Node>),
    Call(Function, Box<Node>),
}

#[derive(Clone, Copy, Debug)]
enum Op {
    Add,
    Sub,
    Mul,
    Div,
    Pow,
}

#[derive(Clone, Copy, Debug)]
enum Function {
    Cos,
    Sin,
    Sqrt,
    Abs,
}

impl Expr {
    /// A constant.
    pub fn constant(value: f64) -> Self {
        Self { source: format_number(value), root: Node::Number(value) }
    }

    /// The value at size (valence) `k` and index `j`.
    pub fn eval(&self, k: usize, j: usize) -> f64 {
        self.root.eval(k as f64, j as f64)
    }

    /// The formula as written.
    pub fn source(&self) -> &str {
        &self.source
    }
}

fn format_number(value: f64) -> String {
    let text = format!("{value}");
    if text.parse::<f64>() == Ok(value) { text } else { format!("{value:e}") }
}

impl Node {
    fn eval(&self, k: f64, j: f64) -> f64 {
        match self {
            Self::Number(x) => *x,
            Self::Size => k,
            Self::Index => j,
            Self::Neg(a) => -a.eval(k, j),
            Self::Binary(op, a, b) => {
                let (a, b) = (a.eval(k, j), b.eval(k, j));
                match op {
                    Op::Add => a + b,
                    Op::Sub => a - b,
                    Op::Mul => a * b,
                    Op::Div => a / b,
                    Op::Pow => a.powf(b),
                }
            }
            Self::Call(f, a) => {
                let a = a.eval(k, j);
                match f {
                    Function::Cos => a.cos(),
                    Function::Sin => a.sin(),
                    Function::Sqrt => a.sqrt(),
                    Function::Abs => a.abs(),
                }
            }
        }
    }
}

impl std::str::FromStr for Expr {
    type Err = ExprError;

    fn from_str(source: &str) -> Result<Self, ExprError> {
        let mut parser = Parser { source, bytes: source.as_bytes(), at: 0, depth: 0 };
        if source.len() > MAX_FORMULA_LENGTH {
            return Err(parser.error(&format!(
                "the formula is {} bytes long, more than the limit of {MAX_FORMULA_LENGTH}",
                source.len()
            )));
        }
        let root = parser.sum()?;
        parser.skip_space();
        if parser.at < parser.bytes.len() {
            return Err(parser.error("unexpected character"));
        }
        Ok(Self { source: source.to_string(), root })
    }
}

impl fmt::Display for Expr {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.source)
    }
}

impl PartialEq for Expr {
    fn eq(&self, other: &Self) -> bool {
        self.source == other.source
    }
}

impl From<f64> for Expr {
    fn from(value: f64) -> Self {
        Self::constant(value)
    }
}

impl Serialize for Expr {
    fn serialize<S: Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        match self.root {
            Node::Number(x) if self.source == format_number(x) => serializer.serialize_f64(x),
            _ => serializer.serialize_str(&self.source),
        }
    }
}

impl<'de> Deserialize<'de> for Expr {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        #[derive(Deserialize)]
        #[serde(untagged)]
        enum Raw {
            Number(f64),
            Text(String),
        }
        match Raw::deserialize(deserializer)? {
            Raw::Number(x) => Ok(Self::constant(x)),
            Raw::Text(text) => text.parse().map_err(serde::de::Error::custom),
        }
    }
}

/// Recursive descent, one level per precedence: sum, product, unary minus, power, atom.
struct Parser<'a> {
    source: &'a str,
    bytes: &'a [u8],
    at: usize,
    /// Levels of nesting entered (see [`MAX_FORMULA_DEPTH`]).
    depth: usize,
}

impl Parser<'_> {
    fn error(&self, message: &str) -> ExprError {
        ExprError { formula: excerpt(self.source, self.at), column: self.at + 1, message: message.to_string() }
    }

    /// `parse` one level deeper, or an error past [`MAX_FORMULA_DEPTH`].
    fn nested(&mut self, parse: impl FnOnce(&mut Self) -> Result<Node, ExprError>) -> Result<Node, ExprError> {
        if self.depth == MAX_FORMULA_DEPTH {
            return Err(self.error(&format!("the formula nests deeper than the limit of {MAX_FORMULA_DEPTH} levels")));
        }
        self.depth += 1;
        let node = parse(self);
        self.depth -= 1;
        node
    }

    fn skip_space(&mut self) {
        while self.bytes.get(self.at).is_some_and(u8::is_ascii_whitespace) {
            self.at += 1;
        }
    }

    fn peek(&mut self) -> Option<u8> {
        self.skip_space();
        self.bytes.get(self.at).copied()
    }

    fn sum(&mut self) -> Result<Node, ExprError> {
        self.left_associative(&[(b'+', Op::Add), (b'-', Op::Sub)], Self::product)
    }

    fn product(&mut self) -> Result<Node, ExprError> {
        self.left_associative(&[(b'*', Op::Mul), (b'/', Op::Div)], Self::unary)
    }

    /// `operand (op operand)*` for one precedence level, folded to the left.
    fn left_associative(
        &mut self,
        ops: &[(u8, Op)],
        operand: fn(&mut Self) -> Result<Node, ExprError>,
    ) -> Result<Node, ExprError> {
        let mut left = operand(self)?;
        while let Some(&(_, op)) = self.peek().and_then(|c| ops.iter().find(|(symbol, _)| *symbol == c)) {
            self.at += 1;
            let right = operand(self)?;
            left = Node::Binary(op, Box::new(left), Box::new(right));
        }
        Ok(left)
    }

    fn unary(&mut self) -> Result<Node, ExprError> {
        if self.peek() == Some(b'-') {
            self.at += 1;
            return Ok(Node::Neg(Box::new(self.nested(Self::unary)?)));
        }
        self.power()
    }

    fn power(&mut self) -> Result<Node, ExprError> {
        let base = self.atom()?;
        if self.peek() == Some(b'^') {
            self.at += 1;
            // Right-associative, and binds tighter than a unary minus on its left: -2^2 = -4.
            let exponent = self.nested(Self::unary)?;
            return Ok(Node::Binary(Op::Pow, Box::new(base), Box::new(exponent)));
        }
        Ok(base)
    }

    fn atom(&mut self) -> Result<Node, ExprError> {
        match self.peek() {
            Some(b'(') => {
                self.at += 1;
                let inner = self.nested(Self::sum)?;
                if self.peek() != Some(b')') {
                    return Err(self.error("expected `)`"));
                }
                self.at += 1;
                Ok(inner)
            }
            Some(c) if c.is_ascii_digit() || c == b'.' => {
                let start = self.at;
                while self.bytes.get(self.at).is_some_and(|c| c.is_ascii_digit() || *c == b'.') {
                    self.at += 1;
                }
                // An exponent: 1e-3, 2.5E+2.
                if self.bytes.get(self.at).is_some_and(|c| matches!(c, b'e' | b'E')) {
                    let mark = self.at;
                    self.at += 1;
                    if self.bytes.get(self.at).is_some_and(|c| matches!(c, b'+' | b'-')) {
                        self.at += 1;
                    }
                    if self.bytes.get(self.at).is_some_and(u8::is_ascii_digit) {
                        while self.bytes.get(self.at).is_some_and(u8::is_ascii_digit) {
                            self.at += 1;
                        }
                    } else {
                        self.at = mark;
                    }
                }
                let text = &self.source[start..self.at];
                text.parse().map(Node::Number).map_err(|_| {
                    self.at = start;
                    self.error("malformed number")
                })
            }
            Some(c) if c.is_ascii_alphabetic() => {
                let start = self.at;
                while self.bytes.get(self.at).is_some_and(|c| c.is_ascii_alphanumeric() || *c == b'_') {
                    self.at += 1;
                }
                let word = &self.source[start..self.at];
                let function = match word {
                    "k" | "n" => return Ok(Node::Size),
                    "j" => return Ok(Node::Index),
                    "pi" => return Ok(Node::Number(std::f64::consts::PI)),
                    "cos" => Function::Cos,
                    "sin" => Function::Sin,
                    "sqrt" => Function::Sqrt,
                    "abs" => Function::Abs,
                    _ => {
                        self.at = start;
                        return Err(self.error(&format!(
                            "unknown name `{word}` (variables: k, n, j; constant: pi; functions: cos, sin, sqrt, abs)"
                        )));
                    }
                };
                if self.peek() != Some(b'(') {
                    return Err(self.error(&format!("expected `(` after `{word}`")));
                }
                let argument = self.nested(Self::atom)?;
                Ok(Node::Call(function, Box::new(argument)))
            }
            Some(_) => Err(self.error("expected a number, a variable, a function or `(`")),
            None => Err(self.error("unexpected end of formula")),
        }
    }
}

/// `source`, or when it is long about 60 bytes of it around byte `at`, cut at character
/// boundaries and marked with `…`.
fn excerpt(source: &str, at: usize) -> String {
    const WIDTH: usize = 60;
    if source.chars().count() <= WIDTH + 20 {
        return source.to_string();
    }
    let boundary = |i: usize| (0..=i.min(source.len())).rev().find(|&b| source.is_char_boundary(b)).unwrap_or(0);
    let start = boundary(at.saturating_sub(WIDTH / 2));
    let end = boundary(start + WIDTH);
    let (head, tail) = (if start > 0 { "…" } else { "" }, if end < source.len() { "…" } else { "" });
    format!("{head}{}{tail}", &source[start..end])
}

#[cfg(test)]
mod tests {
    use super::*;

    fn eval(source: &str, k: usize, j: usize) -> f64 {
        source.parse::<Expr>().unwrap_or_else(|e| panic!("{e}")).eval(k, j)
    }

    #[test]
    fn precedence_and_associativity() {
        assert_eq!(eval("1 + 2 * 3", 0, 0), 7.0);
        assert_eq!(eval("(1 + 2) * 3", 0, 0), 9.0);
        assert_eq!(eval("8 / 4 / 2", 0, 0), 1.0);
        assert_eq!(eval("2 ^ 3 ^ 2", 0, 0), 512.0);
        assert_eq!(eval("-2^2", 0, 0), -4.0);
        assert_eq!(eval("2^-1", 0, 0), 0.5);
        assert_eq!(eval("1 - 2 - 3", 0, 0), -4.0);
        assert_eq!(eval("1.5e1 + .5", 0, 0), 15.5);
    }

    #[test]
    fn variables_and_functions() {
        assert_eq!(eval("(k - 2) / k", 4, 0), 0.5);
        assert_eq!(eval("n * j", 5, 3), 15.0);
        assert!((eval("cos(2*pi/k)", 6, 0) - 0.5).abs() < 1e-15);
        assert_eq!(eval("sqrt(16) + abs(-1) + sin(0)", 0, 0), 5.0);
    }

    #[test]
    fn errors_name_the_column() {
        let e = "1 + * 2".parse::<Expr>().unwrap_err();
        assert_eq!(e.column, 5);
        let e = "cos(x)".parse::<Expr>().unwrap_err();
        assert!(e.message.contains("unknown name `x`"), "{e}");
        assert_eq!(e.column, 5);
        assert!("(1 + 2".parse::<Expr>().unwrap_err().message.contains("`)`"));
        assert!("1 2".parse::<Expr>().unwrap_err().message.contains("unexpected"));
        assert!("".parse::<Expr>().unwrap_err().message.contains("end"));
    }

    #[test]
    fn deep_formulas_are_refused() {
        // 10,000 parentheses overflowed the parser's stack; the limit refuses them, in one short
        // line that quotes the place, not the whole formula.
        for (formula, rule) in [
            (format!("{}1{}", "(".repeat(10_000), ")".repeat(10_000)), "longer"),
            (format!("{}1{}", "(".repeat(1_000), ")".repeat(1_000)), "nests deeper"),
            (format!("{}1", "-".repeat(1_000)), "nests deeper"),
            (format!("2{}", "^2".repeat(1_000)), "nests deeper"),
            (format!("{}1{}", "abs(".repeat(500), ")".repeat(500)), "nests deeper"),
            (format!("1{}", "+1".repeat(3_000)), "longer"),
        ] {
            let e = formula.parse::<Expr>().unwrap_err();
            let text = e.to_string();
            assert!(text.contains(if rule == "longer" { "bytes long" } else { rule }), "{text}");
            assert!(text.len() < 200 && !text.contains('\n'), "{text}");
        }
        let nested = format!("{}1{}", "(".repeat(MAX_FORMULA_DEPTH), ")".repeat(MAX_FORMULA_DEPTH));
        assert_eq!(eval(&nested, 0, 0), 1.0);
        assert_eq!(eval(&format!("1{}", "+1".repeat(2_000)), 0, 0), 2001.0);
        assert_eq!(excerpt("ab", 1), "ab");
        let cut = excerpt(&"é".repeat(100), 100);
        assert!(cut.starts_with('…') && cut.ends_with('…') && cut.len() <= 66, "{cut}");
    }

    #[test]
    fn serde_keeps_the_source() {
        #[derive(Serialize, Deserialize, PartialEq, Debug)]
        struct Holder {
            a: Expr,
            b: Expr,
        }
        let holder: Holder = toml::from_str("a = \"1/k\"\nb = 0.25\n").unwrap();
        assert_eq!(holder.a.eval(4, 0), 0.25);
        assert_eq!(holder.b.eval(0, 0), 0.25);
        let text = toml::to_string(&holder).unwrap();
        assert_eq!(text, "a = \"1/k\"\nb = 0.25\n");
        assert!(toml::from_str::<Holder>("a = \"1/q\"\nb = 1\n").is_err());
    }
}
