//! `#IF` conditions: `DEFINED (X)`, `NOT`, `AND`, `OR`, `TRUE`, `FALSE`, parentheses, and
//! comparisons (`=`, `<>`, `<`, `>`, `<=`, `>=`) of integers, strings and defined names.

use std::collections::HashMap;

/// The value of a `#DEFINE`d symbol or a condition operand.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Value {
    /// An integer (`#DEFINE X 32`).
    Int(i64),
    /// A string (`#DEFINE X "abc"`).
    Str(String),
    /// A truth value; a symbol defined without a value is TRUE.
    Bool(bool),
}

/// Reads a literal value: a decimal or `#hex` integer, a quoted string, TRUE or FALSE.
pub fn literal(text: &str) -> Option<Value> {
    let text = text.trim();
    if let Some(hex) = text.strip_prefix('#') {
        return i64::from_str_radix(hex, 16).ok().map(Value::Int);
    }
    if let Some(inner) = text.strip_prefix('"').and_then(|t| t.strip_suffix('"')) {
        return Some(Value::Str(inner.to_string()));
    }
    match text {
        "TRUE" => Some(Value::Bool(true)),
        "FALSE" => Some(Value::Bool(false)),
        _ => text.parse().ok().map(Value::Int),
    }
}

/// Evaluates a condition; the error says what was wrong.
pub fn evaluate(text: &str, defines: &HashMap<String, Value>) -> Result<bool, String> {
    let tokens = tokenize(text)?;
    let mut parser = Parser {
        tokens,
        pos: 0,
        defines,
        depth: 0,
    };
    let value = parser.or()?;
    match parser.tokens.get(parser.pos) {
        None => truth(&value),
        Some(token) => Err(format!("unexpected `{token}`")),
    }
}

fn truth(value: &Value) -> Result<bool, String> {
    match value {
        Value::Bool(b) => Ok(*b),
        Value::Int(i) => Ok(*i != 0),
        Value::Str(_) => Err("a string is not a truth value".to_string()),
    }
}

fn tokenize(text: &str) -> Result<Vec<String>, String> {
    let mut tokens = Vec::new();
    let mut chars = text.char_indices().peekable();
    while let Some((i, c)) = chars.next() {
        let token = match c {
            ' ' | '\t' => continue,
            '(' | ')' | '=' => c.to_string(),
            '<' | '>' => match chars.peek() {
                Some((_, next @ ('=' | '>'))) if !(c == '>' && *next == '>') => {
                    let t = format!("{c}{next}");
                    chars.next();
                    t
                }
                _ => c.to_string(),
            },
            '"' => {
                let end = text[i + 1..].find('"').ok_or("unterminated string")?;
                for _ in 0..=end {
                    chars.next();
                }
                text[i..i + end + 2].to_string()
            }
            c if c.is_ascii_alphanumeric() || c == '#' || c == '.' || c == '_' => {
                let mut end = i + c.len_utf8();
                while let Some(&(j, d)) = chars.peek() {
                    if !(d.is_ascii_alphanumeric() || d == '.' || d == '_') {
                        break;
                    }
                    end = j + d.len_utf8();
                    chars.next();
                }
                text[i..end].to_string()
            }
            _ => return Err(format!("unexpected character `{c}`")),
        };
        tokens.push(token);
    }
    Ok(tokens)
}

struct Parser<'d> {
    tokens: Vec<String>,
    pos: usize,
    defines: &'d HashMap<String, Value>,
    depth: usize,
}

impl Parser<'_> {
    fn peek(&self) -> Option<&str> {
        self.tokens.get(self.pos).map(String::as_str)
    }

    fn next(&mut self) -> Result<String, String> {
        let token = self
            .tokens
            .get(self.pos)
            .cloned()
            .ok_or("the condition ends too early")?;
        self.pos += 1;
        Ok(token)
    }

    fn expect(&mut self, want: &str) -> Result<(), String> {
        match self.next()? {
            t if t == want => Ok(()),
            t => Err(format!("expected `{want}`, found `{t}`")),
        }
    }

    fn or(&mut self) -> Result<Value, String> {
        let mut value = self.and()?;
        while self.peek() == Some("OR") {
            self.pos += 1;
            let rhs = self.and()?;
            value = Value::Bool(truth(&value)? || truth(&rhs)?);
        }
        Ok(value)
    }

    fn and(&mut self) -> Result<Value, String> {
        let mut value = self.comparison()?;
        while self.peek() == Some("AND") {
            self.pos += 1;
            let rhs = self.comparison()?;
            value = Value::Bool(truth(&value)? && truth(&rhs)?);
        }
        Ok(value)
    }

    fn comparison(&mut self) -> Result<Value, String> {
        let lhs = self.unary()?;
        let Some(op) = self
            .peek()
            .filter(|t| ["=", "<>", "<", ">", "<=", ">="].contains(t))
        else {
            return Ok(lhs);
        };
        let op = op.to_string();
        self.pos += 1;
        let rhs = self.unary()?;
        compare(&op, &lhs, &rhs).map(Value::Bool)
    }

    fn unary(&mut self) -> Result<Value, String> {
        self.depth += 1;
        if self.depth > 200 {
            return Err("the condition is nested too deeply".to_string());
        }
        let value = self.unary_inner();
        self.depth -= 1;
        value
    }

    fn unary_inner(&mut self) -> Result<Value, String> {
        let token = self.next()?;
        match token.as_str() {
            "NOT" => Ok(Value::Bool(!truth(&self.unary()?)?)),
            "(" => {
                let value = self.or()?;
                self.expect(")")?;
                Ok(value)
            }
            "DEFINED" => {
                self.expect("(")?;
                let name = self.next()?;
                self.expect(")")?;
                Ok(Value::Bool(self.defines.contains_key(&name)))
            }
            _ => literal(&token)
                .or_else(|| self.defines.get(&token).cloned())
                .ok_or_else(|| format!("`{token}` is not defined")),
        }
    }
}

fn compare(op: &str, lhs: &Value, rhs: &Value) -> Result<bool, String> {
    let ordering = match (lhs, rhs) {
        (Value::Int(a), Value::Int(b)) => a.cmp(b),
        (Value::Str(a), Value::Str(b)) => a.cmp(b),
        (Value::Bool(a), Value::Bool(b)) => a.cmp(b),
        _ => return Err("cannot compare values of different kinds".to_string()),
    };
    Ok(match op {
        "=" => ordering.is_eq(),
        "<>" => ordering.is_ne(),
        "<" => ordering.is_lt(),
        ">" => ordering.is_gt(),
        "<=" => ordering.is_le(),
        _ => ordering.is_ge(),
    })
}
