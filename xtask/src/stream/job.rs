//! What the streamer knows about the job before sending it: which file
//! lines pause the machine, change tools or carry an operator message, so
//! that what the board reports (a `Hold`, a `[MSG:…]`, a sequence number)
//! can be told back to the person in terms of the file.

/// Why a line stops the program.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PauseKind {
    /// M0: program pause.
    Stop,
    /// M1: optional stop (burin honours it).
    Optional,
    /// M6: manual tool change; the tool number, if the file names one.
    Tool(Option<u32>),
}

/// A program pause at a file line (1-based).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Pause {
    pub line: usize,
    pub kind: PauseKind,
}

/// The job file, read once.
pub struct Job {
    pub name: String,
    pub lines: Vec<String>,
    /// Program pauses in file order.
    pub pauses: Vec<Pause>,
    /// `(MSG,…)` / M117 texts with their file lines, in file order.
    pub messages: Vec<(usize, String)>,
}

impl Job {
    pub fn new(name: String, source: &str) -> Job {
        let lines: Vec<String> = source.lines().map(str::to_string).collect();
        let mut pauses = Vec::new();
        let mut messages = Vec::new();
        let mut tool = None;
        for (i, l) in lines.iter().enumerate() {
            let (words, comments) = split(l);
            for c in &comments {
                let t = c.trim_start();
                if t.len() >= 4 && t[..4].eq_ignore_ascii_case("msg,") {
                    messages.push((i + 1, t[4..].trim().to_string()));
                }
            }
            let mut kind = None;
            for &(letter, value) in &words {
                // Whole numbers only: M0.5 is not M0.
                let n = (value.fract() == 0.0 && value >= 0.0).then_some(value as u32);
                match (letter, n) {
                    ('T', Some(t)) => tool = Some(t),
                    ('M', Some(0)) => kind = Some(PauseKind::Stop),
                    ('M', Some(1)) => kind = Some(PauseKind::Optional),
                    ('M', Some(6)) => kind = Some(PauseKind::Tool(None)),
                    ('M', Some(117)) => {
                        let at = l.to_ascii_uppercase().find("M117").map_or(0, |p| p + 4);
                        messages.push((i + 1, l[at..].trim().to_string()));
                    }
                    _ => {}
                }
            }
            if let Some(mut k) = kind {
                if k == PauseKind::Tool(None) {
                    k = PauseKind::Tool(tool);
                }
                pauses.push(Pause {
                    line: i + 1,
                    kind: k,
                });
            }
        }
        Job {
            name,
            lines,
            pauses,
            messages,
        }
    }

    /// `file:line`, or the file alone for line 0 (not a job line).
    pub fn at(&self, line: usize) -> String {
        if line == 0 {
            self.name.clone()
        } else {
            format!("{}:{line}", self.name)
        }
    }
}

/// A line's words (letter, number) and its comment texts. Enough G-code
/// to find M0/M1/M6/T/M117 and `(MSG,…)`; the board does the real parsing.
fn split(line: &str) -> (Vec<(char, f64)>, Vec<String>) {
    let mut words = Vec::new();
    let mut comments = Vec::new();
    let mut chars = line.chars().peekable();
    while let Some(c) = chars.next() {
        match c {
            '(' => {
                let mut text = String::new();
                for c in chars.by_ref() {
                    if c == ')' {
                        break;
                    }
                    text.push(c);
                }
                comments.push(text);
            }
            ';' => {
                comments.push(chars.by_ref().collect());
            }
            c if c.is_ascii_alphabetic() => {
                let mut num = String::new();
                while let Some(&d) = chars.peek() {
                    if d.is_ascii_digit() || d == '.' || d == '-' || d == '+' || d == ' ' {
                        if d != ' ' {
                            num.push(d);
                        }
                        chars.next();
                    } else {
                        break;
                    }
                }
                if let Ok(v) = num.parse() {
                    words.push((c.to_ascii_uppercase(), v));
                }
            }
            _ => {}
        }
    }
    (words, comments)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn finds_pauses_tools_and_messages() {
        let j = Job::new(
            "j".into(),
            "(msg,note axis)\nm0\nG1 X1 T3\nM6\nM1 (MSG, again)\nG0 X2 ; m0 in a comment\nM117 Hi there",
        );
        assert_eq!(
            j.pauses,
            vec![
                Pause {
                    line: 2,
                    kind: PauseKind::Stop
                },
                Pause {
                    line: 4,
                    kind: PauseKind::Tool(Some(3))
                },
                Pause {
                    line: 5,
                    kind: PauseKind::Optional
                },
            ]
        );
        assert_eq!(
            j.messages,
            vec![
                (1, "note axis".to_string()),
                (5, "again".to_string()),
                (7, "Hi there".to_string())
            ]
        );
    }
}
