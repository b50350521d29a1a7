//! A generator of small timed MAVLink protocols: two or three roles (`GCS`, `UAV`, `CAM`),
//! requests answered before a timeout, floods ended by a silence, re-request loops with a
//! retry counter, nested choices, a third role told something inside the branches, answers
//! that must carry the index asked for, continuations that repeat the timeout branch or jump
//! back to the choice. The shapes are the ones E0326 decides between; a few labels are used
//! over and over so that a late message often has the label of a reception.

/// A tiny deterministic generator of choices (xorshift), seeded by the test runner.
pub struct Rng(u64);

impl Rng {
    pub fn new(seed: u64) -> Rng {
        Rng(seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1)
    }
    fn next(&mut self) -> u64 {
        let mut x = self.0;
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        self.0 = x;
        x
    }
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n as u64) as usize
    }
    fn chance(&mut self, percent: u64) -> bool {
        self.next() % 100 < percent
    }
    fn pick<'a>(&mut self, xs: &[&'a str]) -> &'a str {
        xs[self.below(xs.len())]
    }
}

/// An enclosing loop the generated type may jump to.
#[derive(Clone)]
struct Loop {
    name: String,
    /// The retry counter, if any (a jump passes `n - 1`; only under its `[n > 0]` branch).
    counter: Option<String>,
    /// Whether a jump here is allowed at this point (a flood only straight from its branch).
    open: bool,
}

pub struct Gen {
    rng: Rng,
    three: bool,
    fresh: usize,
    /// Labels of this protocol: few, so that they recur.
    up: Vec<&'static str>,
    down: Vec<&'static str>,
    third: &'static str,
}

const UP: &[&str] = &["PARAM_VALUE", "MISSION_COUNT", "MISSION_ACK", "STATUSTEXT"];
const DOWN: &[&str] = &["PARAM_REQUEST_READ", "PARAM_SET", "MISSION_REQUEST_LIST", "PARAM_REQUEST_LIST"];

impl Gen {
    pub fn new(seed: u64) -> Gen {
        let mut rng = Rng::new(seed);
        let three = rng.chance(25);
        let mut up = vec![rng.pick(UP), rng.pick(UP)];
        up.dedup();
        let mut down = vec![rng.pick(DOWN), rng.pick(DOWN)];
        down.dedup();
        let third = rng.pick(&["STATUSTEXT", "PARAM_SET"]);
        Gen { rng, three, fresh: 0, up, down, third }
    }

    /// A whole protocol's source.
    pub fn protocol(&mut self) -> String {
        let body = self.g(3, &[]);
        let (cam, body) = if self.three && !body.contains("CAM") {
            (" participant CAM;", format!("GCS -> CAM: {}. {body}", self.third))
        } else if self.three {
            (" participant CAM;", body)
        } else {
            ("", body)
        };
        format!("dialect common;\nsystem S {{ participant GCS; participant UAV;{cam} }}\nchoreography G =\n  {body};\n")
    }

    fn id(&mut self) -> usize {
        self.fresh += 1;
        self.fresh
    }

    /// Roles `(S, W)`: the sender and the waiting role of a choice.
    fn pair(&mut self) -> (&'static str, &'static str) {
        if self.rng.chance(70) {
            ("UAV", "GCS")
        } else {
            ("GCS", "UAV")
        }
    }

    fn label(&mut self, from: &str) -> &'static str {
        let xs = if from == "UAV" { self.up.clone() } else { self.down.clone() };
        xs[self.rng.below(xs.len())]
    }

    fn two_labels(&mut self, from: &str) -> (&'static str, &'static str) {
        let pool = if from == "UAV" { UP } else { DOWN };
        let a = self.label(from);
        let mut b = self.rng.pick(pool);
        while b == a {
            b = self.rng.pick(pool);
        }
        (a, b)
    }

    /// A continuation: `end`, a jump, or more steps.
    fn g(&mut self, depth: u32, loops: &[Loop]) -> String {
        let jumps: Vec<&Loop> = loops.iter().filter(|l| l.open).collect();
        if depth == 0 {
            if !jumps.is_empty() && self.rng.chance(50) {
                let l = jumps[self.rng.below(jumps.len())].clone();
                return jump(&l);
            }
            return "end".into();
        }
        match self.rng.below(10) {
            0 => "end".into(),
            1 if !jumps.is_empty() => {
                let l = jumps[self.rng.below(jumps.len())].clone();
                jump(&l)
            }
            2 if self.three => {
                let from = if self.rng.chance(50) { "GCS" } else { "UAV" };
                let rest = self.g(depth - 1, loops);
                format!("{from} -> CAM: {}. {rest}", self.third)
            }
            3 => {
                let (s, w) = self.pair();
                let l = self.label(s);
                let rest = self.g(depth - 1, loops);
                format!("{s} -> {w}: {l}. {rest}")
            }
            4 => self.counter_loop(depth, loops),
            5 => self.flood(depth, loops),
            6 => {
                let (s, w) = self.pair();
                let (a, b) = self.two_labels(s);
                let ga = self.g(depth - 1, loops);
                let gb = self.g(depth - 1, loops);
                format!("( {s} -> {w}: {a}. {ga} + {s} -> {w}: {b}. {gb} )")
            }
            _ => self.timed(depth, loops),
        }
    }

    /// `( S -> W: l. G_1 [+ S -> W: l'. G_2] + after T ms by W. G_t )`.
    fn timed(&mut self, depth: u32, loops: &[Loop]) -> String {
        let (s, w) = self.pair();
        let t = [500, 1000, 1500][self.rng.below(3)];
        let gt = self.timeout_branch(s, w, depth, loops);
        let (a, b) = self.two_labels(s);
        let mut branches = Vec::new();
        for l in [a, b].into_iter().take(if self.rng.chance(30) { 2 } else { 1 }) {
            let cont = match self.rng.below(4) {
                0 | 1 => gt.clone(),
                _ => self.g(depth - 1, loops),
            };
            branches.push(format!("{s} -> {w}: {l}. {cont}"));
        }
        format!("( {} + after {t} ms by {w}. {gt} )", branches.join(" + "))
    }

    /// What the waiting role does after giving up: it speaks first (E0324), or ends, or
    /// spends a retry.
    fn timeout_branch(&mut self, s: &str, w: &str, depth: u32, loops: &[Loop]) -> String {
        let counted: Vec<&Loop> = loops.iter().filter(|l| l.counter.is_some() && l.open).collect();
        match self.rng.below(4) {
            0 => "end".into(),
            1 if !counted.is_empty() => {
                let l = counted[self.rng.below(counted.len())].clone();
                jump(&l)
            }
            _ => {
                let l = self.label(w);
                let rest = self.g(depth.saturating_sub(1), loops);
                format!("{w} -> {s}: {l}. {rest}")
            }
        }
    }

    /// A re-request loop with a retry counter; the request may fix an index that the answer
    /// must carry.
    fn counter_loop(&mut self, depth: u32, loops: &[Loop]) -> String {
        let k = self.id();
        let (name, n) = (format!("t{k}"), format!("n{k}"));
        let mut inner: Vec<Loop> = loops.to_vec();
        inner.push(Loop { name: name.clone(), counter: Some(n.clone()), open: true });
        let (ask, answer) = if self.rng.chance(35) {
            let w = format!("w{k}");
            let g = format!("g{k}");
            (
                format!("PARAM_REQUEST_READ(param_index as {w} {{0 <= {w} && {w} <= 1}})"),
                format!("PARAM_VALUE(param_index as {g} {{{g} == {w}}})"),
            )
        } else {
            (self.label("GCS").to_string(), self.label("UAV").to_string())
        };
        let t = [500, 1000][self.rng.below(2)];
        let after_answer = match self.rng.below(3) {
            0 => format!("{name}({n} - 1)"),
            1 => "end".into(),
            _ => self.g(depth - 1, &inner),
        };
        let gt = match self.rng.below(3) {
            0 => format!("{name}({n} - 1)"),
            _ => self.timeout_branch("UAV", "GCS", depth - 1, &inner),
        };
        let stop = if self.rng.chance(50) {
            let l = self.label("GCS");
            format!("GCS -> UAV: [{n} <= 0] {l}. end")
        } else {
            format!("after {} ms by UAV. end", t * 3)
        };
        format!(
            "( mu {name}({n}: int {{0 <= {n} && {n} <= 2}} = 2) decreases {n}. ( GCS -> UAV: [{n} > 0] {ask}. ( UAV -> GCS: {answer}. {after_answer} + after {t} ms by GCS. {gt} ) + {stop} ) )"
        )
    }

    /// `mu f. ( UAV -> GCS: l. f + after T ms by GCS. G )`, with a request first at times.
    fn flood(&mut self, depth: u32, loops: &[Loop]) -> String {
        let k = self.id();
        let name = format!("f{k}");
        let closed: Vec<Loop> = loops.to_vec();
        let l = self.label("UAV");
        let gt = self.timeout_branch("UAV", "GCS", depth - 1, &closed);
        let head = if self.rng.chance(50) {
            let r = self.label("GCS");
            format!("GCS -> UAV: {r}. ")
        } else {
            String::new()
        };
        format!("{head}( mu {name}. ( UAV -> GCS: {l}. {name} + after 1000 ms by GCS. {gt} ) )")
    }
}

fn jump(l: &Loop) -> String {
    match &l.counter {
        Some(n) => format!("{}({n} - 1)", l.name),
        None => l.name.clone(),
    }
}
