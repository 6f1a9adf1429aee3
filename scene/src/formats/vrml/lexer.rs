//! Tokens (§5.1): the text split into words, numbers, strings and brackets, each with its
//! line and column.

use std::path::Path;

use crate::error::SceneError;

/// A line and column (1-based, columns counted in characters).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Pos {
    pub line: u32,
    pub column: u32,
}

#[derive(Clone, Debug, PartialEq)]
pub(super) enum Tok {
    Word(String),
    Num(f64),
    Str(String),
    Open,
    Close,
    OpenList,
    CloseList,
}

#[derive(Clone, Debug)]
pub(super) struct Token {
    pub tok: Tok,
    pub pos: Pos,
}

/// How a token reads in "expected …, found …" messages.
pub(super) fn describe(token: Option<&Token>) -> String {
    match token.map(|t| &t.tok) {
        None => "the end of the file".to_string(),
        Some(Tok::Word(w)) => format!("`{w}`"),
        Some(Tok::Num(n)) => format!("the number {n}"),
        Some(Tok::Str(s)) => {
            let s: String = s.chars().take(30).collect();
            format!("the string \"{s}\"")
        }
        Some(Tok::Open) => "`{`".to_string(),
        Some(Tok::Close) => "`}`".to_string(),
        Some(Tok::OpenList) => "`[`".to_string(),
        Some(Tok::CloseList) => "`]`".to_string(),
    }
}

/// §5.1: whitespace is space, tab, line feed, carriage return and comma.
fn is_space(c: char) -> bool {
    matches!(c, ' ' | '\t' | '\n' | '\r' | ',')
}

/// Characters that end a word or number (§5.5 excludes them from identifiers).
fn is_delimiter(c: char) -> bool {
    is_space(c) || matches!(c, '{' | '}' | '[' | ']' | '"' | '#' | '\'' | '\\')
}

/// Splits the text into tokens one at a time (so a large file is never held twice), keeping
/// each token's line and column.
pub(super) struct Lexer<'a> {
    chars: std::iter::Peekable<std::str::Chars<'a>>,
    line: u32,
    column: u32,
    path: &'a Path,
}

impl<'a> Lexer<'a> {
    pub fn new(text: &'a str, path: &'a Path) -> Self {
        Lexer { chars: text.chars().peekable(), line: 1, column: 1, path }
    }

    pub fn pos(&self) -> Pos {
        Pos { line: self.line, column: self.column }
    }

    /// One character, keeping the position.
    fn bump(&mut self) -> Option<char> {
        let c = self.chars.next();
        if c == Some('\n') {
            self.line = self.line.saturating_add(1);
            self.column = 1;
        } else if c.is_some() {
            self.column = self.column.saturating_add(1);
        }
        c
    }

    fn error(&self, pos: Pos, problem: impl Into<String>) -> SceneError {
        SceneError::syntax(self.path, pos.line as usize, pos.column as usize, problem)
    }

    /// The next token, or `None` at the end of the text.
    pub fn next_token(&mut self) -> crate::Result<Option<Token>> {
        while let Some(&c) = self.chars.peek() {
            let pos = self.pos();
            if is_space(c) {
                self.bump();
                continue;
            }
            if c == '#' {
                while self.chars.peek().is_some_and(|&c| c != '\n' && c != '\r') {
                    self.bump();
                }
                continue;
            }
            let single = match c {
                '{' => Some(Tok::Open),
                '}' => Some(Tok::Close),
                '[' => Some(Tok::OpenList),
                ']' => Some(Tok::CloseList),
                _ => None,
            };
            if let Some(tok) = single {
                self.bump();
                return Ok(Some(Token { tok, pos }));
            }
            if c == '"' {
                return self.string(pos).map(Some);
            }
            let mut word = String::new();
            while let Some(&c) = self.chars.peek() {
                if is_delimiter(c) {
                    break;
                }
                word.push(c);
                self.bump();
            }
            if word.is_empty() {
                // A lone `'` or `\`: not part of any VRML97 token.
                return Err(self.error(
                    pos,
                    format!("expected a node, field or value, found the character `{c}`"),
                ));
            }
            let tok = if c.is_ascii_digit() || matches!(c, '+' | '-' | '.') {
                match parse_number(&word) {
                    Some(n) => Tok::Num(n),
                    None => {
                        return Err(self.error(pos, format!("expected a number, found `{word}`")));
                    }
                }
            } else {
                Tok::Word(word)
            };
            return Ok(Some(Token { tok, pos }));
        }
        Ok(None)
    }

    /// §5.1: a string in double quotes, where `\"` and `\\` stand for `"` and `\`.
    fn string(&mut self, pos: Pos) -> crate::Result<Token> {
        self.bump();
        let mut s = String::new();
        loop {
            match self.bump() {
                None => {
                    return Err(self.error(
                        pos,
                        "expected a closing `\"` for the string that starts here, found the end \
                         of the file; close the string",
                    ));
                }
                Some('"') => return Ok(Token { tok: Tok::Str(s), pos }),
                Some('\\') => match self.bump() {
                    Some(e @ ('"' | '\\')) => s.push(e),
                    Some(other) => {
                        s.push('\\');
                        s.push(other);
                    }
                    None => {}
                },
                Some(other) => s.push(other),
            }
        }
    }
}

/// A number as §5.3 writes them: decimal floats and integers, and `0x` hexadecimal integers.
/// Overflow gives an infinity, refused where the number is used.
fn parse_number(word: &str) -> Option<f64> {
    let (negative, digits) = match word.as_bytes().first() {
        Some(b'-') => (true, &word[1..]),
        Some(b'+') => (false, &word[1..]),
        _ => (false, word),
    };
    if let Some(hex) = digits.strip_prefix("0x").or_else(|| digits.strip_prefix("0X")) {
        if hex.is_empty() || !hex.chars().all(|c| c.is_ascii_hexdigit()) {
            return None;
        }
        let value = i64::from_str_radix(hex, 16).ok()? as f64;
        return Some(if negative { -value } else { value });
    }
    if !word.chars().all(|c| c.is_ascii_digit() || matches!(c, '+' | '-' | '.' | 'e' | 'E')) {
        return None;
    }
    word.parse::<f64>().ok()
}

// ---------------------------------------------------------------------------------------------
// Syntax tree (§4.4, §5): nodes with their fields, whatever the node type.
