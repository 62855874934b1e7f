//! The interpreter's scanner (the manual's INTERP\SCANNER.C): a line into tokens, each with
//! the column where it starts, so that an error can point at it.

/// What a token is.
#[derive(Clone, Debug, PartialEq)]
pub enum Kind {
    /// A word: a command, a location name (`test_001`, `#park`), a keyword (`straight`).
    Word(String),
    /// A number (`-90`, `1.5707963`, `1e3`).
    Number(f64),
    /// `(`.
    Open,
    /// `)`.
    Close,
    /// `,`.
    Comma,
}

/// A token and where it is.
#[derive(Clone, Debug, PartialEq)]
pub struct Token {
    /// What it is.
    pub kind: Kind,
    /// Its first column, 1-based (characters).
    pub col: usize,
    /// Its text.
    pub text: String,
}

/// A line that cannot be read: where and what was expected.
#[derive(Clone, Debug, PartialEq)]
pub struct SyntaxError {
    /// Column, 1-based.
    pub col: usize,
    /// How many columns to mark.
    pub width: usize,
    /// What is wrong and what was expected.
    pub message: String,
}

impl SyntaxError {
    pub fn at(token: &Token, message: impl Into<String>) -> SyntaxError {
        SyntaxError {
            col: token.col,
            width: token.text.chars().count().max(1),
            message: message.into(),
        }
    }

    /// The line with a caret line under the offending columns.
    pub fn render(&self, line: &str) -> String {
        // The line's own tabs in the padding, so that the caret stands under the column
        // however wide the terminal draws a tab.
        let pad: String = line
            .chars()
            .take(self.col.saturating_sub(1))
            .map(|c| if c == '\t' { '\t' } else { ' ' })
            .collect();
        format!("  {line}\n  {pad}{}", "^".repeat(self.width))
    }
}

/// Split a line into tokens. `;` starts a comment that runs to the end of the line.
pub fn scan(line: &str) -> Result<Vec<Token>, SyntaxError> {
    let chars: Vec<char> = line.chars().collect();
    let mut out = Vec::new();
    let mut i = 0;
    while i < chars.len() {
        let c = chars[i];
        let col = i + 1;
        let single = |kind: Kind| Token {
            kind,
            col,
            text: c.to_string(),
        };
        match c {
            ';' => break,
            c if c.is_whitespace() => i += 1,
            '(' => {
                out.push(single(Kind::Open));
                i += 1;
            }
            ')' => {
                out.push(single(Kind::Close));
                i += 1;
            }
            ',' => {
                out.push(single(Kind::Comma));
                i += 1;
            }
            c if c.is_ascii_digit() || c == '-' || c == '+' || c == '.' => {
                let start = i;
                i += 1;
                while i < chars.len() {
                    let d = chars[i];
                    let exp_sign = (d == '-' || d == '+') && matches!(chars[i - 1], 'e' | 'E');
                    if d.is_ascii_alphanumeric() || d == '.' || d == '_' || exp_sign {
                        i += 1;
                    } else {
                        break;
                    }
                }
                let text: String = chars[start..i].iter().collect();
                let value = text.parse::<f64>().ok().filter(|v| v.is_finite());
                match value {
                    Some(v) => out.push(Token {
                        kind: Kind::Number(v),
                        col,
                        text,
                    }),
                    None => {
                        return Err(SyntaxError {
                            col,
                            width: text.chars().count(),
                            message: format!(
                                "`{text}` is not a number; expected digits with an optional \
                                 sign, point and exponent, like -90, 1.5708 or 1e3"
                            ),
                        });
                    }
                }
            }
            c if c.is_ascii_alphabetic() || c == '#' || c == '_' => {
                let start = i;
                i += 1;
                while i < chars.len() && (chars[i].is_ascii_alphanumeric() || chars[i] == '_') {
                    i += 1;
                }
                let text: String = chars[start..i].iter().collect();
                out.push(Token {
                    kind: Kind::Word(text.clone()),
                    col,
                    text,
                });
            }
            other => {
                return Err(SyntaxError {
                    col,
                    width: 1,
                    message: format!(
                        "unexpected character `{other}`; expected a command, a number, a \
                         location name or a location literal such as c(400, 0, 150)"
                    ),
                });
            }
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tokens_and_columns() {
        let t = scan("appro test_001 c(-90, 0) 1 ; comment").unwrap();
        let kinds: Vec<&Kind> = t.iter().map(|t| &t.kind).collect();
        assert_eq!(
            kinds,
            [
                &Kind::Word("appro".into()),
                &Kind::Word("test_001".into()),
                &Kind::Word("c".into()),
                &Kind::Open,
                &Kind::Number(-90.0),
                &Kind::Comma,
                &Kind::Number(0.0),
                &Kind::Close,
                &Kind::Number(1.0),
            ]
        );
        assert_eq!(t[1].col, 7);
        assert_eq!(t[4].col, 18);
        assert_eq!(scan("x 1e-3").unwrap()[1].kind, Kind::Number(1e-3));
        assert_eq!(
            scan("move #park").unwrap()[1].kind,
            Kind::Word("#park".into())
        );
    }

    #[test]
    fn bad_characters_and_numbers_point_at_their_column() {
        let e = scan("close 6o").unwrap_err();
        assert_eq!((e.col, e.width), (7, 2));
        let e = scan("home @").unwrap_err();
        assert_eq!(e.col, 6);
        assert_eq!(e.render("home @"), "  home @\n       ^");
        // A tab before the column stays a tab under it.
        let line = "speed\t\tabc";
        let tokens = scan(line).unwrap();
        let e = SyntaxError::at(&tokens[1], "x");
        assert_eq!(e.render(line), "  speed\t\tabc\n       \t\t^^^");
    }
}
