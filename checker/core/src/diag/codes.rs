//! The diagnostic codes: the `codes!` table, one entry per code with its number, title and
//! `mochi explain` paragraph, and the [`Code`] enum it defines. Grouped by stage as
//! `diag.rs` says; a new code is an entry here (docs/adding-a-check.md).

/// Each entry is `Variant = "E0000", "title", "explain text";`. An entry written
/// `Variant = "E0000" (reserved), ...` is a code no check produces any more (or not yet):
/// it keeps its number (a code never changes meaning) and `mochi explain` and
/// `mochi explain --list` show it as reserved (the title says so).
macro_rules! codes {
    ($($variant:ident = $code:literal $(($reserved:ident))?, $title:literal, $explain:literal;)*) => {
        /// A stable diagnostic code.
        #[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
        pub enum Code { $($variant,)* }

        impl Code {
            /// Every code, in numeric order.
            pub const ALL: &'static [Code] = &[$(Code::$variant,)*];

            /// The code as users type it, e.g. `E0301`.
            pub fn as_str(self) -> &'static str {
                match self { $(Code::$variant => $code,)* }
            }

            /// A short lowercase title; a reserved code's ends in `(reserved: never produced)`.
            pub fn title(self) -> &'static str {
                match self { $(Code::$variant => concat!($title $(, " (", stringify!($reserved), ": never produced)")?),)* }
            }

            /// The paragraph printed by `mochi explain CODE`; a reserved code's starts with
            /// `reserved: `.
            pub fn explain(self) -> &'static str {
                match self {
                    $(Code::$variant => concat!($(stringify!($reserved), ": no check produces this code; it keeps its number so that it never changes meaning. ",)? $explain),)*
                }
            }

            /// Whether the code is reserved: no check produces it.
            pub fn is_reserved(self) -> bool {
                match self { $(Code::$variant => false $(|| stringify!($reserved) == "reserved")?,)* }
            }
        }
    };
}

codes! {
    UnexpectedChar = "E0101", "unexpected character",
        "The lexer met a character that starts no token of mochi's language. mochi files are ASCII: \
         identifiers, numbers, strings in double quotes, `//` and `/* */` comments, and the \
         punctuation listed in LANGUAGE.md. Remove the character or replace a typographic symbol \
         by its ASCII spelling (for example `->` for an arrow, `&&` for a conjunction).";
    Unterminated = "E0102", "unterminated comment or string",
        "A block comment `/* ...` or a string `\"...` runs to the end of the file. Close it with \
         `*/` or `\"` on the same logical item.";
    UnexpectedToken = "E0103", "unexpected token",
        "The parser expected one kind of token and found another. The message lists what would \
         have been accepted at that point. mochi recovers at the next `;` or top-level keyword, \
         so later errors in the same item may be consequences of this one.";
    BadNumber = "E0104", "malformed number",
        "A numeric literal could not be read: integers must fit in 64 bits and reals are written \
         with digits on both sides of the point, as in `0.65` or `1.0e-3`.";
    ImportNotFound = "E0105", "imported file cannot be read",
        "An `import \"path\";` names a file that does not exist or cannot be read. Paths are \
         relative to the importing file. Each file is loaded once, so import cycles are harmless.";
    NotSourceFile = "E0106", "not a mochi source file",
        "An `import` names something mochi does not read as source: a file whose name does not end \
         in `.mochi` or `.chor`, a directory, a device, a FIFO or a socket (reading `/dev/zero` or \
         `/dev/urandom` would never end), or a file larger than 64 MiB. Imports may point outside \
         the importing file's directory, so that projects can share libraries, but only at regular \
         mochi files. Rename or move the file, or import the library that declares what you need.";
    NotUtf8 = "E0107", "invalid utf-8 in a source file",
        "A source file, an imported file or standard input contains bytes that are not UTF-8. The \
         message gives the first bad byte with its offset, line and column. mochi source is ASCII \
         outside comments and strings; save the file as UTF-8 (a UTF-8 byte-order mark at the start \
         is accepted and skipped).";
    TooDeep = "E0108", "nesting too deep",
        "A term is nested deeper than 1000 levels. Every kind of nesting counts: parentheses, \
         prefixes such as `-` and `!`, `mu`, `if`, and chains of binary operators such as \
         `a + b + c` or `2 ^ 2 ^ 2` (each operator is a level of the term's tree). A sequence of \
         steps (`p -> q : a. q -> p : b. ...`, or `q!a.p?b. ...` in processes and local types) is \
         not nesting and may be as long as the file allows. Split a deep term with named constants.";
    UnknownRobot = "E0201", "unknown robot kind",
        "A participant or a motion primitive names a robot kind that no `robot` declaration \
         defines. Declare it, or import the file of `robots/` that does.";
    UnknownParticipant = "E0202", "unknown participant",
        "A choreography, process, local type or qualified variable names a participant that the \
         `system` does not declare. Every role must be declared once as `participant Name: Kind`.";
    UnknownPrimitive = "E0203", "unknown motion primitive",
        "A joint motion `dt<p: a>` or a process motion names a primitive `a` that is not declared \
         for the robot kind of `p` (Def 4.4 (3): a motion primitive must exist for each \
         participant). Declare `motion Kind.a(...) { ... }` or use a primitive of that kind.";
    ArityMismatch = "E0204", "wrong number of arguments",
        "A motion primitive, recursion variable or message is used with a different number of \
         arguments than it declares. Pass exactly one argument per declared parameter.";
    UnknownVariable = "E0205", "unknown variable",
        "An expression names a variable that is neither a constant, a parameter, a state or input \
         variable of the robot in question, nor a value received or sent earlier in the protocol.";
    Duplicate = "E0206", "duplicate definition",
        "A name is defined twice in the same namespace: two robot kinds, two primitives of one \
         kind, two participants, two fields of one motion, two variables of one robot, or two \
         processes for one role. In a program with a MAVLink `dialect`: a `const` named like an \
         enum entry of the dialect (every entry is an `int` constant), or one field of a MAVLink \
         message listed twice (a command's `action` and `param1` included). Rename or delete one \
         of them.";
    UnboundRecursion = "E0207", "unbound recursion variable",
        "A recursion variable `t` is used outside any `mu t. ...` that binds it (Def 4.1: types \
         are closed). Bind it with `mu t.` around the recursive part.";
    SortMismatch = "E0208", "sort mismatch",
        "An expression has the wrong sort: a predicate must be `bool`, arithmetic needs `int` or \
         `real` (ints are promoted to reals), components need a `point` or `vector`. The message \
         says which sort was expected and which was found.";
    UnconnectedInput = "E0209", "input variable not connected",
        "Sec 3.1: an input variable `w` of a participant takes its value from the unique other \
         participant with a state variable named `w`. None, or more than one, exists. Rename the \
         input or the state variables so that exactly one other participant provides it.";
    MissingItem = "E0210", "missing system or choreography",
        "`mochi check` needs one `system` block and one `choreography` in the files it reads. \
         A `.chor` file, or standard input, without them is E0210, and so is a program with only \
         one of the two. A `.mochi` library with neither (the files under `robots/` and \
         `motion-primitives/`) is checked on its own instead: its kinds' invariants and its \
         primitives' contracts (E0411, E0409, E0412; see E0420).";
    VariableNotAllowed = "E0211", "variable not allowed in this part of a contract",
        "Def 3.4 fixes what each part of a motion primitive may read: pre- and postconditions read \
         state and input variables; the assumption reads inputs and `clock`; the guarantee reads \
         state variables and `clock`; the footprint reads state variables, its point and `clock`. \
         `old(x)` is the value of a state variable when the motion started. Parameters and \
         constants may appear everywhere.";
    MissingField = "E0212", "missing field",
        "A motion primitive must say whether it can be interrupted by a message \
         (`interruptible: true;`) or not (`interruptible: false;`), Def 3.4. Other fields default \
         to the weakest contract: `true` predicates, a footprint filling space, duration `[0, inf]`. \
         An obstacle must have a `geometry:` (an obstacle without one would occupy nothing).";
    ConstCycle = "E0213", "constants defined in a cycle",
        "Constants may be declared in any order, but a constant's value cannot depend on itself, \
         directly (`const a = a + 1;`) or through other constants (`const a = b; const b = a;`). \
         The message names the cycle. Give one of the constants a value that does not mention the \
         others.";
    BadShape = "E0214", "unknown shape or wrong shape arguments",
        "A body (a robot's `geometry:`, a geometric `footprint:`, an obstacle's `geometry:`) is \
         a sum of shapes `part + part + ...`, each optionally placed by `at pose(...)`. The shapes \
         are `box(lx, ly, lz)`, `sphere(r)`, `cylinder(r, h)`, `capsule(r, h)` with real sizes in \
         metres, and `urdf(\"file.urdf\")` and `mesh(\"file.stl\")` (or `.obj`) naming a file \
         relative to the file that names it. Any other name, another number of arguments, a path \
         given to a sized shape or numbers given to a file shape is E0214.";
    NoOwnGeometry = "E0215", "`footprint: geometry` in a robot kind without geometry",
        "`footprint: geometry;` makes a primitive's footprint the robot's own body, placed by its \
         state at every time of the motion. The robot kind declares no `geometry:`, so there is \
         no body to use. Give the kind a `geometry:` (shapes or a URDF), or write the footprint's \
         shapes in the primitive (`footprint: box(...) at pose(...);`) or as a predicate \
         (`footprint(px, py, pz): ...;`).";
    MountCycle = "E0216", "a participant is mounted on itself or in a cycle of mounts",
        "`on: Carrier.mount` places a participant on a frame of another participant, which moves \
         with the carrier's state. A participant cannot ride on itself, and the carriers cannot \
         form a cycle (`A` on `B` and `B` on `A`): the world pose of each would depend on itself. \
         The message names the cycle. Mount the robots in a chain that ends at a participant \
         placed in the world.";
    ObstacleAsParticipant = "E0217", "an obstacle is named where a participant is expected",
        "An obstacle (`obstacle Name { ... }` in a system) is static geometry: it has no state, no \
         process and takes part in no message or motion. Naming it as a sender, a receiver, a \
         moving participant, the role of a `process` or `local`, or reading `Name.var`, is \
         E0217. Make it a participant with a robot kind if it must move or communicate.";
    UnknownMount = "E0218", "unknown mount",
        "`on: Carrier.mount` names a mount point that the carrier's robot kind does not declare. \
         A robot offers mounts with `mount name: pose(...);` in its `robot` block; the message \
         lists the ones it has.";
    UnknownDialect = "E0230", "unknown mavlink dialect",
        "`dialect NAME;` names the MAVLink dialect whose messages a protocol exchanges. mochi \
         bundles the dialects of the MAVLink XML definitions (`common`, `ardupilotmega`, \
         `standard`, `minimal` and the others shipped under `checker/core/src/dialect/definitions/`); the \
         message lists them and the closest names. Dialects are read at build time: a user XML \
         file cannot be named yet.";
    DialectConflict = "E0231", "two different dialects",
        "A program (the `.chor` file and every file it imports) speaks one MAVLink dialect: \
         each message label, field and enum entry is resolved in it. Two `dialect` items naming \
         different dialects are an error (the same name twice is harmless). A dialect such as \
         `ardupilotmega` includes `common`: name the larger one.";
    UnknownMessage = "E0232", "unknown mavlink message",
        "In a program with a `dialect`, every message label is a MAVLink message of that \
         dialect, by its XML name (`MISSION_COUNT`, `COMMAND_LONG[MAV_CMD_X]`). The label \
         names none; the help lists the closest names (by edit distance). Without a `dialect`, \
         labels are free.";
    UnknownField = "E0233", "unknown field of a mavlink message",
        "A payload field of a MAVLink message must be one of the message's fields (`count` of \
         `MISSION_COUNT`), or for `COMMAND_LONG[MAV_CMD_X]` and `COMMAND_INT[MAV_CMD_X]` one of \
         its parameters, by `param1`..`param7` or by the parameter's XML label in snake case \
         (`action` for MAV_CMD_DO_PARACHUTE's \"Action\"). The help lists the closest names.";
    WireSort = "E0234", "a field's sort disagrees with its wire type",
        "A MAVLink field's sort comes from its wire type: `uint8_t`..`uint64_t` and \
         `int8_t`..`int64_t` are `int`, `float` and `double` are `real`, `char[N]` is `str`. A \
         `: sort` written after the field must be that sort (it may be left out).";
    ArrayField = "E0235", "an array field cannot be used",
        "A MAVLink field of an array type other than `char[N]` (`uint8_t[32]`, `float[4]`) has \
         no sort in mochi yet: it can neither be listed in a payload nor read by a refinement. \
         Leave it out of the message's payload: a field not listed may have any value of its \
         wire type.";
    StringTooLong = "E0236", "a string that may be longer than its field",
        "A `char[N]` field holds at most N characters; a string literal compared with it is \
         longer, so the comparison could never be true (or `!=` never false). Use the name as the \
         autopilot spells it (parameter ids are at most 16 characters). The checks read a \
         string as one value without a length, so a field's refinement may compare it (`==`) \
         only with values at most N wide, and a process may send in it only such values: the \
         wire keeps the first N characters of a longer one.";
    BadKey = "E0237", "a label key the message cannot carry (no such command, or no single string field)",
        "`COMMAND_LONG[MAV_CMD_X]` and `COMMAND_INT[MAV_CMD_X]` are the command messages with \
         their `command` field fixed to the entry `MAV_CMD_X` of the enum `MAV_CMD`. The command \
         must be such an entry, the message one with a `command` field of enum `MAV_CMD`, and \
         the program must name a `dialect`. A key `PARAM_VALUE[\"MC_PITCH_P\"]` fixes the \
         message's one `char[N]` field: a message with none, or several, takes no key.";
    ReservedParam = "E0238", "a reserved command parameter is named",
        "A `MAV_CMD` parameter the dialect marks `reserved=\"true\"` must not be used (it is sent \
         as 0 or NaN and means nothing). Remove it from the payload.";
    BadFlag = "E0239", "`has_flag` needs an integer and a constant flag",
        "`has_flag(x, F)` is true iff every bit set in F is set in the integer x (MAVLink bitmask \
         enums such as MAV_MODE_FLAG). F must be a constant positive integer: an entry of a \
         bitmask enum, an integer literal or a constant with such a value; x must be of sort \
         `int`.";
    ShadowsEntry = "E0240", "a name hides an enum entry of the dialect",
        "In a program with a `dialect`, every enum entry (`MAV_MISSION_ACCEPTED`, \
         `MAV_CMD_DO_PARACHUTE`) is an `int` constant. A payload binder, recursion parameter, \
         received value, motion parameter or robot variable of the same name would hide it \
         from every expression after it, silently changing what the name means. Choose another \
         name. (A `const` of an entry's name is E0206.)";
    MissingSort = "E0241", "a payload field without a sort",
        "A payload field of a message that is not a MAVLink message must say its sort \
         (`x: real`). Only the fields of a MAVLink message (a program with a `dialect`) take \
         their sorts from the dialect, and only they may be renamed with `FIELD as NAME`.";
    ProtocolOnly = "E0242", "a protocol only: no process typed",
        "A note, not an error. A program with no `process` item at all is a protocol (a \
         MAVLink sub-protocol between a ground station and a vehicle, or a robot cell checked \
         before its programs exist): mochi checks its global type (well-formedness, total \
         choice, recursion parameters, every refinement and guard on its path, and for robots \
         the initial states, compatibility, collisions, separation and the primitives' \
         contracts) and projects it onto each participant, but no process is typed against \
         its projection, so `verified` says nothing of an implementation (a motion's \
         precondition is checked only against a process's state, and is assumed here). `mochi project FILE --role R` prints what a process of R must do. \
         With one `process`, every participant needs one (E0701).";
    NotAnEntry = "E0243", "a refinement admits no entry of the field's enum",
        "A MAVLink field or command parameter whose dialect definition names an enum \
         (`enum=\"MAV_RESULT\"`; MAV_CMD_COMPONENT_ARM_DISARM's param1 is a `MAV_BOOL`) carries \
         an entry of that enum, and for an enum marked `bitmask=\"true\"` (MAV_MODE_FLAG) a \
         combination of its flags (each bit it sets is set by some flag; 0 included). That is \
         part of the field's type, like its wire range: a refinement narrows it (`{type != \
         MAV_MISSION_ACCEPTED}` of MISSION_ACK is the fifteen error results), the receiver \
         assumes it, and a process must send such a value ([T-OUT], E0709). A float parameter \
         carries the entry's value exactly (`1.0`, not `1.001`). E0243 is a refinement that \
         leaves no such value where the message is sent (with the guard and what is known \
         there), although it admits values of the wire type: the message names the enum and, \
         when it is short, its entries or flags, and the counterexample is a value the \
         refinement admits. A receiver could decode no such message. Compare with the entries' \
         names (`{arm == MAV_BOOL_TRUE}`, flags summed or tested with `has_flag`).";
    DeprecatedMessage = "E0244", "a deprecated mavlink message",
        "A warning, not an error. The dialect marks the message `<deprecated>` or \
         `<superseded>` (MISSION_REQUEST and MISSION_ITEM, replaced by their `_INT` forms in \
         2020; SET_MODE, superseded by the command MAV_CMD_DO_SET_MODE). The protocol is \
         checked as written: autopilots still send some deprecated messages, and a protocol \
         that must accept them (`choreographies/mavlink/mission-upload-tolerant.chor`) lists \
         them on purpose. The warning names the replacement the XML gives, once per message, \
         at its first use. (Deprecated enum entries are not reported: the dialect reader does \
         not read their deprecation.)";
    ObservedOutsideMessage = "E0245", "an observed value read where no snapshot is taken",
        "A field of a `stream` declaration is observed state: the latest value its reader has \
         received, which may change between any two steps of the session. mochi takes a snapshot \
         of it where a participant decides, at a message's guard and refinements (one snapshot per \
         message, shared by the first messages of a choice), and nowhere else: a recursion \
         parameter's initial value or refinement, a jump's arguments, a loop's measure and a \
         motion's arguments are read by several participants or at several times, and an \
         observed value has no one value there. To carry a reading into the loop, send it: \
         `GCS -> UAV: MSG(field as h {h == relative_alt})` binds `h`, a value both ends hold.";
    StepIsStreamed = "E0246", "a protocol step that a stream also carries",
        "A `stream FROM -> TO: LABEL` says `FROM` sends `LABEL` to `TO` at any time, as \
         telemetry that is no step of the session. A message `FROM -> TO: LABEL` of the \
         choreography (the same label, or the same MAVLink message with and without a fixed \
         command) would be indistinguishable on the wire from the stream's messages: a monitor \
         could not tell the step from telemetry, and the session would advance on any of the \
         stream's messages. Drop the step (read the stream's latest value in a guard instead), or \
         the stream.";
    SelfMessage = "E0301", "message to oneself",
        "Def 4.1 requires `p != q` in `p -> q : l`. A participant cannot send a message to itself; \
         use a local computation in its process instead.";
    DuplicateLabel = "E0302", "duplicate label in a choice",
        "Def 4.1 requires distinct labels `l_i != l_j` among the branches of a choice, so the \
         receiver can tell which branch was taken. Rename one of the labels.";
    ChoiceMismatch = "E0303", "choice branches do not start with the same sender and receiver",
        "Def 4.1: every branch `g_i` of `g_1 + ... + g_n` starts with a message `p -> q` with the \
         same `p` and `q`, so that `p` decides and `q` learns the decision. Start every branch \
         with a message from the same sender to the same receiver (different labels), and tell \
         other participants in a second message.";
    UnguardedRecursion = "E0304", "unguarded recursion",
        "Def 4.1 postulates guarded recursion: between `mu t.` and an occurrence of `t` there must \
         be at least one message or motion. `mu t. t` has no meaning.";
    GuardNotLocal = "E0305", "guard or refinement reads a variable its sender does not know",
        "Def 4.1: `fv(P) ⊆ p.X ∪ p.W` for the guard of `p -> q : [P] l`, and the refinement may \
         also read the value variable. mochi also lets a sender read values it sent or received \
         earlier. Motion arguments in `dt<p: a(e)>` follow the same rule for `p`. Move the test \
         to the participant that owns the variable, or send the value first.";
    DuplicateMotionParticipant = "E0306", "participant moves twice in one joint motion",
        "A joint motion `dt<p1: a1, ..., pn: an>` gives one primitive to each participant; the \
         participants must be distinct (a robot executes one motion primitive at a time).";
    SeparationOverlap = "E0307", "participant on both sides of `*`",
        "Sec 4.1: `g1 * g2` is fully separated only if `pt{g1} ∩ pt{g2} = ∅`: the two sides are \
         independent groups that neither communicate nor move together until they merge. Move \
         the shared participant's actions out of one side.";
    OutOfScope = "E0308", "participant out of scope",
        "Well-scopedness (Sec 4.1, rules (1)-(6)): each node of the once-unfolded choreography is \
         labelled with the participants in scope; a `*` splits the scope in two. A message or \
         motion that involves a participant outside its scope cannot be labelled. This typically \
         happens when a recursion variable, unfolded, lands inside one side of a `*`.";
    IncompleteMotion = "E0309", "joint motion leaves a participant in scope without a primitive",
        "Def 4.4 (3), total motion: a joint motion `dt<...>` must give a motion primitive to every \
         participant in scope, because time passes for all of them. Add `p: idle`-like primitives \
         for the missing participants, or split them off with `*`.";
    NotUniqueMinimal = "E0310", "no unique minimal communication after a motion",
        "Synchronisability (Sec 4.1): every joint motion must have a unique immediate \
         happens-before edge to a message `p -> q`: the message that ends it. When two messages \
         can come first (say `p -> q` and `r -> q`), the participants in the motion cannot know \
         whose message interrupts them. Order the messages through a common sender.";
    SenderNotReady = "E0311", "sender of the message after a motion is not ready",
        "Sender readiness (Sec 4.1): the message that ends a joint motion must be sent by the \
         participant executing the only non-interruptible primitive, or every primitive of the \
         motion must be interruptible. Otherwise the sender could still be in the middle of a \
         motion it cannot stop. Make the other primitives interruptible or change the sender.";
    NotTotallySynchronised = "E0312", "participant changes motion without being told",
        "Total synchronisation (Sec 4.1, Example 4.2): between two joint motions ordered by \
         happens-before, every participant of the first must send or receive a message, or it \
         cannot know when to switch primitive. mochi accepts one documented exception \
         (ARCHITECTURE.md): a lone participant whose primitive is non-interruptible may chain \
         into another motion of its own, since it switches when its motion ends.";
    ParticipantUnused = "E0313", "participant takes no part in the choreography",
        "[T-SESS] requires `pt{G} = P`: every declared participant appears in the choreography. \
         Remove the participant from the system or give it a role.";
    NotTailPosition = "E0314", "nothing may follow `end`, a recursion or its variable",
        "Def 4.1: `G ::= g.G | t | mu t.G` — recursion and its variables (and `end`) close a \
         sequence. Move what follows into the recursion body.";
    CoupledAcrossSeparation = "E0315", "motions on two sides of `*` are coupled through inputs",
        "Sec 4.1, full separation: the assumption of a primitive in `g_i` may only depend on \
         state variables of participants in `pt{g_i}`. An input variable connected to a \
         participant on the other side couples the two groups. Put both participants on one side.";
    TwoNonInterruptible = "E0401", "non-interruptible primitives of a joint motion that may end apart",
        "[AGCOMP] (Sec 3.4) as printed allows at most one non-interruptible primitive in a joint \
         motion (‡1 = ↯ ∨ ‡2 = ↯): the participant running it ends the motion ([NON-INTERRUPT], \
         Fig 3) and sends next (sender readiness, Sec 4.1); with two, who ends first is unknown. \
         mochi accepts several when their durations force a common end (joint end): every \
         non-interruptible part's duration is a single instant [d, d], the same d for all, under \
         what is known when the motion starts (the context Σ and the preconditions), compared as \
         exact reals (0.1 + 0.2 is 0.3; 0.30000000000000004 is not). Then all of them end at d, \
         and any of them may send next. Otherwise this error: give them the same duration \
         [d, d], or make all but one interruptible.";
    Unmergeable = "E0601", "projection cannot merge two branches",
        "Projection (Def 4.8 (3)) of a choice onto a participant that neither sends nor receives \
         the choosing message merges the projections of the branches (Def 4.7). Merging succeeds \
         when they are equal, when both are receptions from the same sender (possibly with a \
         default motion), or when one is a motion and the other receptions with that default. \
         The participant cannot tell which branch was taken; inform it with a message.";
    LocalMismatch = "E0602", "declared local type does not fit the projection",
        "A `local R = T;` item states the local type `R`'s process is typed against. By [T-SUB] \
         (Table 1) that is sound when `T` is a subtype of the projection of the choreography onto \
         `R` (Def 4.10, Fig 5): `T` may send fewer labels, receive more, use primitives that refine \
         the projection's, and carry stronger send and weaker receive predicates (those are checked \
         as E0711 and E0407). E0602 is the structural part: at the point shown `T` does an action \
         of another kind, sends a label or receives from a sender the projection does not allow, \
         misses a label it may be sent, carries a different number of values, or runs a primitive \
         of another interruptibility or robot kind. A type equal to \
         the projection always fits; `mochi project FILE --role R` prints it.";
    MissingProcess = "E0701", "participant has no process",
        "[T-SESS] types one process per participant. Add `process R = ...;` for the participant.";
    ActionMismatch = "E0702", "process action does not match the local type",
        "Process typing (Table 1): at this point the local type expects a different action (send, \
         receive, motion, recursion or end) than the process performs. The message shows both.";
    MissingBranch = "E0703", "process does not handle a message the type may deliver",
        "[T-CHOICE1/2] and [SUB-IN]: an external choice in the process must offer every label the \
         local type may receive from that sender; it may offer more. Add the missing branch.";
    UnexpectedSend = "E0704", "process sends a message the type does not allow",
        "[T-OUT] and [SUB-OUT]: each send must match a branch of the internal choice in the local \
         type, with the same receiver and label.";
    PrimitiveMismatch = "E0705", "process motion cannot refine the type's motion",
        "[SUB-MOTION] lets a process run a primitive that refines the one in the type (Def 3.4, \
         corrected direction). Refinement requires the same robot kind and the same \
         interruptibility; the predicate and duration conditions are proof obligations.";
    RecursionMismatch = "E0706", "process recursion does not match the local type",
        "[T-REC]: a process variable must stand where its recursion is expected; the process loops \
         to a different point than the type, or exits a loop the type keeps.";
    PayloadArity = "E0707", "wrong number of values in a message",
        "A send or receive in a process carries a different number of values than the message of \
         the local type declares.";
    ChoiceNotTotal = "E0316", "the guards of a choice do not cover every state",
        "Def 4.4 (1), total choice: in every state that can reach a choice, at least one branch's \
         guard must hold, or the choreography could get stuck there. Z3 found a state (shown as the \
         counterexample: the values of the variables the guards read, under what is known at that \
         point) where every guard is false. Add a branch for that case, or weaken a guard.";
    UnsynchronisedStart = "E0317", "participants of a joint motion may start it at different times",
        "A joint motion dt<p: a, q: b> is checked by [AGCOMP] (Sec 3.4) as if all its primitives \
         started together, and Def 4.11 (6) consumes it at one time for all. Each participant starts \
         its part when its previous message happens (or its lone non-interruptible motion ends). \
         After `g1 * g2` the sides run at independent times (Sec 4.1), so participants released by \
         messages on different sides may start at different times: one runs its new primitive while \
         another is still in its old one, and nothing checks that. Sec 4.1's rules accept this shape \
         (a gap in the paper). mochi requires every participant of a joint motion to be released at \
         the same instant: by the same burst of messages, which happens when one sender becomes ready \
         (its motion ends) and every receiver is in an interruptible motion or already in the burst. \
         The durations count: a receiver whose side's non-interruptible motions end, by their \
         durations (evaluated from their arguments), no later than the sender's is ready when the \
         message comes, so a relay after `*` (P tells Q, Q at once tells V) is one instant when \
         the sides' durations say so. \
         Fix: end the other sides in interruptible motions and let one side's last sender tell each of \
         them, as Example 4.2 (4) does, or keep the joint motion on one side of the `*`.";
    UncheckedOverlap = "E0318", "two motions may run at the same time with nothing checking them together",
        "Footprints are compared only for motions known to run together: the primitives of one dt \
         ([AGCOMP], Sec 3.4) and the motions of the two sides of one `*` (full separation, Sec 4.1, at \
         independent times). Two motions of different participants that nothing orders in time (no \
         chain of messages and motions from the end of one to the start of the other) may also \
         overlap, for example the motions of two `*` in a row when one side of the first may still \
         be moving while the other has started the second. Sec 4.1 accepts this (a gap in the \
         paper); mochi rejects it. Order the two motions with a message, or put them on the two \
         sides of one `*`. Likewise two interruptible primitives of one dt that run on after the \
         dt ends (interrupted later, or never before `end`) while a third primitive's contract \
         bounded the times [AGCOMP] compared them. The check reads each path through the choices of the once-unfolded \
         type, choice by choice where every participant is synchronised between the choices (each \
         last took part in a message at one instant, no primitive running); beyond 4,096 paths \
         between two such points it gives up with this code rather than pass unchecked: end each \
         branch with a burst of messages after its last motion.";
    InterruptOutsideDuration = "E0319", "a message may interrupt a motion outside its duration",
        "Fig 3 [INTERRUPT] consumes an interruptible motion only while its clock t is in its \
         duration D (Def 4.11 (5), (8b)); its contract, and every check of its footprint, speaks of \
         D only. A message ending an interruptible motion is on time when it comes in the burst \
         that ends that same motion: its non-interruptible partner ends within D ([AGCOMP], E0405), \
         or, with all primitives interruptible, its unique minimal sender sends within the shared \
         duration (Def 4.11 (8b)). A message timed by anything else (a motion of arbitrary length \
         on the other side of `*`, or a later motion) may come at any time, so mochi requires the \
         interrupted primitive to be ready at any time: D = [0, inf] (with a literal lower bound) \
         and an assumption that reads no input (after its partners have moved on, their guarantees \
         no longer discharge it). An interruptible motion that nothing interrupts before `end` runs \
         on forever: its duration needs no upper bound, and if its assumption reads inputs, its \
         partners in the dt must run on too. Send the message in the burst that ends the motion, or \
         change the primitive.";
    TimeoutBound = "E0320", "a timeout's bound is not a positive integer constant",
        "The bound `T` of a timeout branch `after T ms by R. G` is a number of milliseconds that a \
         monitor compares with the log's or the clock's time, so it must be known before the \
         session starts: an integer constant expression (literals, `const`s, `+ - *`) whose value is \
         positive. A bound that reads a message's value or a recursion parameter has no one value \
         for the monitor, and a bound of 0 or less would let `R` give up before any message could \
         arrive. Write the bound as a positive integer, or a `const` holding one (`after 1500 ms by \
         GCS`).";
    TimeoutNotInChoice = "E0321", "a timeout branch outside a choice",
        "`after T ms by R. G` is the timeout branch of a choice: `R` waits for the first message of \
         one of the choice's other branches and takes `G` when none came within `T`. It must start \
         a branch of `+` whose other branches start with messages to `R`. Alone, or after another \
         step of a branch, there is nothing to wait for. Make it a branch of the choice it ends: \
         `(p -> R: item. t + after 1000 ms by R. end)`.";
    TwoTimeouts = "E0322", "two timeout branches in one choice",
        "A choice has at most one timeout branch: when no message came within the bound, `R` \
         must know which branch to take, and of two timeout branches the one with the smaller \
         bound would always be taken first. Keep one `after T ms by R` branch per choice.";
    TimeoutNotWaiting = "E0323", "a timeout is taken by a participant that does not wait in the choice",
        "Only the receiver of a choice can time out: in `p -> R: a. G1 + after T ms by R. G2`, `R` \
         waits for `p`'s decision and decides itself, by silence, when it does not come. `p` decides \
         the other branches and cannot observe `R`'s clock, and a third participant is not part of \
         the choice. Name the choice's receiver after `by`, or send the other branches to the \
         participant that waits.";
    TimeoutUnheard = "E0324", "the sender of a choice does not learn that its peer timed out",
        "When `R` takes the timeout branch `after T ms by R. G` of a choice whose messages `p` \
         sends, `p` has not decided anything: it must learn of `R`'s decision in `G` before it acts \
         again. So `G`'s first step is a message from `R` to `p` (a re-request, an error \
         acknowledgement: the first message of a choice sent by `R` to `p`), or `G` is `end` (the \
         session is over for both). Start the timeout branch with `R -> p`, or end it.";
    TimeoutInProcess = "E0325", "a process typed against a protocol with a timeout: not supported yet",
        "Processes are typed against their local types (Table 1), but the process language has no \
         timeout: the waiting role's process cannot give up, and the sender's process would have \
         to expect the waiting role's message after a timeout at every point of the branch it \
         chose. The protocol is still checked as a protocol (well-formedness, total choice, \
         progress, termination and knowledge). Remove the `process` items to check the protocol \
         alone.";
    TimeoutCrossing = "E0326", "a message of a choice can cross the waiting role's timeout",
        "On a real link a message takes time: at a choice `( p -> R: l. G + ... + after T ms by R. \
         G_t )`, `p` may send `l` just as `R` gives up, so `p` goes on in `G` while `R` goes on in \
         `G_t`, and `l` reaches `R` late. mochi accepts the choice when no such run meets an \
         unexpected message: (1) after each message branch `p` still accepts `R`'s first message \
         of `G_t`, because the branch goes on exactly as `G_t` does, or jumps straight back to the \
         choice with its loop's parameters unchanged (whose timeout alternative is `p`'s part of \
         `G_t`); (2) where `R` next receives from `p` in `G_t`, the late message's label is not \
         expected (`R` ignores it as late), or is expected by a branch with no guard and no \
         refinement that jumps straight back to that reception (`R` absorbs it); (3) no third \
         participant takes part in the branches before they jump or end. Otherwise `R` reads the \
         late message as the answer to its next request (mavlink/mavlink#950's race) or `p` meets \
         a message its branch does not expect. Make the branch go on as the timeout branch, loop \
         back to the choice, or accept any late message where `R` next waits \
         (docs/observed-and-timeouts.md, \"The timeout crossing\").";
    PreconditionAtMotion = "E0402", "a primitive's precondition may not hold when the joint motion starts",
        "[AGCOMP] composes primitives from their preconditions (Sec 3.4, \"compatible from Pre\"): \
         at the `dt<...>` each participant's precondition must follow from what is known there \
         (initial states, the postconditions of earlier motions, guards and refinements of \
         messages received). The counterexample is a state allowed by that context in which the \
         precondition is false. Establish it with an earlier motion or message, or weaken it.";
    AssumptionNotDischarged = "E0403", "an assumption is not discharged by the other guarantees",
        "[AGCOMP] (Sec 3.4): the assumption A of each primitive of a joint motion must follow from \
         the guarantees G of the others, at every time of the motion, with no leftover assumption. \
         The counterexample gives a time and states in which every other guarantee holds and the \
         assumption is false. Strengthen a partner's guarantee or weaken the assumption.";
    FootprintsOverlap = "E0404", "the footprints of a joint motion may overlap",
        "[AGCOMP] (Sec 3.4): the footprints of the primitives of a joint motion must be disjoint at \
         every time of the motion, given their guarantees. The counterexample is a point of the world \
         (x, y, z, in metres) and a time (seconds since the motion started) at which both footprints \
         contain the point, with every participant's state at that time and at the motion's start. The \
         time is also given since the choreography started when nothing before the motion on the path \
         takes time (messages take none), and said to be undetermined otherwise. mochi bisects the \
         time: it names a time at or before which the footprints are proved not to meet, so the first \
         meeting lies between the two; it never calls a meeting the earliest without that proof. A footprint may cover space swept over \
         the whole motion (Sec 3.5's cart box grows with time), so the point need not be where the robot's \
         body is at that instant, only where its footprint allows it to be. Move a participant (its pose or the \
         target of its motion), shrink a footprint, or strengthen a guarantee (for example, make an \
         arm stay up while a cart approaches, as Sec 3.5 does).";
    DurationsIncompatible = "E0405", "the durations of a joint motion do not fit together",
        "[AGCOMP] (Sec 3.4): a non-interruptible primitive's duration D must lie within the \
         duration of every interruptible partner (D1 ⊆ D2), so that the partners are ready whenever \
         it ends; with only interruptible primitives, their durations must share a time. Adjust \
         the `duration:` bounds, or make the long primitive interruptible.";
    SidesOverlap = "E0406", "the two sides of `*` may occupy the same space",
        "Full separation (Sec 4.1): the sides of `g1 * g2` run without synchronising, so all the \
         footprints one side may use must be disjoint from all those of the other side, at any \
         times. mochi first tries boxes around each side's footprints (the inferred partition); \
         when they meet it asks Z3 about each pair of motions. The counterexample shows a point and \
         the two motions' times. Keep the sides apart, or put the motions that meet in one joint \
         motion so that [AGCOMP] checks them together.";
    RefinementFails = "E0407", "a primitive does not refine the one the type expects",
        "Def 3.4 in the corrected direction (seeds README, error 1): a concrete primitive c \
         implements an abstract s when Pre_s => Pre_c, A_s => A_c, G_c => G_s, Post_c => Post_s, \
         FP_c ⊆ FP_s at every state and time, both are (non-)interruptible alike, and for \
         durations D_s ⊆ D_c (interruptible) or D_c ⊆ D_s (non-interruptible). The message names \
         the item that fails and the counterexample the states where it does.";
    MotionCannotEnd = "E0408", "a motion primitive cannot end in a state its robot allows",
        "Every joint motion must be able to finish (Sec 3.4 relies on contracts being deadlock \
         free: from the precondition a trajectory exists). mochi checks that, from what is known \
         when the primitive starts, some end state satisfies its postcondition and its robot \
         kind's invariant. When none does (for example `m_move(12)` for a cart whose invariant \
         keeps it within 10 m), everything after the motion would hold vacuously, so this is an \
         error. Change the motion's arguments, or its postcondition or the invariant.";
    VacuousContract = "E0409", "a motion primitive can never end",
        "A primitive's contract must admit at least one run that ends ([NON-INTERRUPT] and \
         [INTERRUPT], Fig 3: the elapsed time t lies in the duration D, the guarantee held over \
         [0, t] and the postcondition holds at t). mochi asks, for every primitive the \
         protocol runs, whether some start state allowed by the precondition and the kind's \
         invariant, some arguments and some t in D admit an end state satisfying the guarantee at \
         t, the postcondition and the invariant. When none does (an empty duration such as \
         `[2, 1]` or `[-2, -1]`, a postcondition that contradicts the guarantee), any motion using \
         it deadlocks and everything after it would hold vacuously. Fix the duration's bounds, or \
         make the guarantee and the postcondition agree at the end.";
    StuckContext = "E0410", "a reachable point of the protocol has an unsatisfiable context",
        "The logical context Σ (what holds at a point: the initial states, the guards and \
         refinements of the messages so far, the postconditions of the motions so far) became \
         unsatisfiable through a step the protocol takes: an `init` no state satisfies, a \
         message's refinement or guard that contradicts what holds. No execution gets past that \
         step, so the protocol is stuck there, and every check after it would hold vacuously. The \
         error points at the step that made Σ unsatisfiable. As a warning, the same code marks a \
         branch of a choice whose guard can never hold where it is offered (a dead branch: its \
         checks hold vacuously and are not evidence of anything).";
    InitOutsideInvariant = "E0411", "no initial state lies within its robot's invariant",
        "A robot's state satisfies its kind's `invariant` at every time, the first included, so \
         the initial context of a participant is its `init` together with the invariant ([T-SESS] \
         assumes both). mochi asks that some state satisfies both: an `init` whose every state \
         the invariant excludes describes a robot that cannot exist, and were it accepted the \
         initial context would be false and everything after it hold vacuously. (An `init` may \
         leave the invariant's bounds implicit, as `ze >= clear_z` does for an arm whose \
         invariant caps `ze`: the first state is then any state satisfying both.) Fix `init` or \
         the invariant so that they have a state in common.";
    EmptyFootprint = "E0412", "a primitive's footprint holds no point",
        "A footprint is the space the robot may occupy while the primitive runs, so it contains the \
         robot's geometry at every state the guarantee allows (Sec 3.1: FP contains geom(p)); mochi \
         trusts that it does (until geometry is checked) and proves collision freedom from \
         footprints. A footprint that no point satisfies (`false`, or bounds that contradict each \
         other) would make every collision check about the primitive hold vacuously: two such \
         robots on top of each other would be verified. mochi asks, for each primitive the \
         protocol runs, whether some start state its precondition and the kind's invariant allow \
         has a point in the footprint at time 0. A kind with no `geometry:` whose every footprint is literally `false` is \
         bodiless (an environment, a sensor) and is not asked. Fix the footprint so that it \
         contains the robot.";
    RecInitRefinement = "E0414", "a recursion parameter's initial value breaks its refinement",
        "Parameterised recursion (DATUM's `mu T(n : S {P}) <n = e>`, mochi's \
         `mu t(n: S {P} = e). G`): the refinement P is what every iteration of the loop may assume \
         of n, so it must hold of the initial value e when the loop is entered, under what is known \
         there. The counterexample is a state allowed at the entry in which P[e/n] is false. \
         Start the parameter at a value that satisfies its refinement, or weaken the refinement.";
    RecJumpRefinement = "E0415", "a jump back to a loop breaks its parameter's refinement",
        "Parameterised recursion: at each `t(a)` the arguments become the parameters' values for \
         the next iteration, which assumes their refinement P. So P[a/n] must hold under what is \
         known at the jump, on every path that reaches it. The counterexample is a state (with the \
         current parameters) that reaches the jump with arguments that break P. Guard the branch \
         that jumps (for example `[n > 0]` before `t(n - 1)`), or change the arguments.";
    MeasureNegative = "E0416", "a loop's termination measure may be negative at a jump back",
        "Termination of refined recursion (`mu t(params) decreases E. G`; DATUM seed 000 Sec 3.1's \
         `mu T(n: Z {P}) <n = e>` with a measure): the loop claims to be left after finitely many \
         iterations because the integer E is bounded below by 0 and drops at every jump back. \
         So at each `t(a)`, on every path that reaches it (under what is known there: the \
         messages' refinements, the guards on the way, the parameters' refinements), E >= 0 must \
         hold of the current iteration. The counterexample is a state reaching the jump with a \
         negative E. Guard the branch that jumps (for example `[i < count]`), or choose a measure \
         that stays non-negative.";
    MeasureNotDecreasing = "E0417", "a loop's termination measure does not decrease at a jump back",
        "Termination of refined recursion (`mu t(params) decreases E. G`): at each jump `t(a)` the \
         measure of the next iteration, E with the arguments for the parameters, must be smaller \
         than E of the current one, on every path to the jump. Otherwise the loop can repeat \
         forever (a counter never incremented: `t(i)` instead of `t(i + 1)`). The counterexample \
         gives the parameters and payload values for which E[a/params] >= E. Pass arguments that \
         make progress, or drop `decreases` if the loop is meant to run forever (a reactive loop: \
         then nothing is claimed).";
    MeasureNoExit = "E0418", "a loop with a termination measure has no way out",
        "`mu t(params) decreases E. G` claims that the loop ends, but no path of its body reaches \
         `end` or a jump to an enclosing loop: every path jumps back to `t` (or to a loop inside \
         it), so the claim is false whatever E is (the measure's checks would then only say that \
         the protocol is stuck once E runs out). Add the branch that leaves the loop (for example \
         the acknowledgement that ends a mission upload), or drop `decreases` for a reactive loop.";
    Stuck = "E0419", "the protocol can get stuck: no branch can be taken",
        "Progress: in every state the protocol reaches, some way on must be open. A message \
         `p -> q: [P] l(v: S {R})` can be sent only when its guard P holds and some value \
         satisfies its refinement R (with the wire ranges of its fields); a choice only when one \
         of its branches can. Total choice (E0316) asks that the guards cover every state; this \
         check asks more: that in every state allowed there (the guards' disjunction assumed, \
         E0316 checks it), some branch has a true guard and a payload its refinement admits. The \
         counterexample is such a state, in the values of the messages and parameters so far, \
         and the trace is the path that reaches it. Weaken the refinement, or add a branch for \
         that state (for example a NACK).";
    EmptyLibrary = "E0420", "a library declares no robot kind and no motion primitive",
        "A note, not an error. `mochi check lib.mochi` checks a library on its own when the file \
         (with its imports) has no `system` and no `choreography`: its names and sorts, that each \
         robot kind's invariant admits a state (E0411), that each motion primitive can end (E0409) \
         and that each footprint of a kind with a body holds a point (E0412). A library with \
         neither kinds nor primitives (constants only) has nothing beyond names and sorts to \
         check; the verdict is `verified` and this note says how little that means.";
    SmtDumpFailed = "E0430", "a solver query could not be dumped",
        "With `--dump-smt DIR`, every query the SMT stage asks Z3 is written to DIR as an SMT-LIB \
         file. When one cannot be written (the disk is full, DIR was removed or made read-only \
         during the run), mochi says so once, at the obligation whose query it was, and dumps no \
         more; the checks themselves are not affected (this is a warning, the verdict stands). \
         Make DIR writable, free space, or run without `--dump-smt`.";
    BadShapeSize = "E0511", "a shape's size is not a positive constant",
        "A body (a robot's `geometry:`, a geometric `footprint:`, an obstacle) is made of shapes \
         whose sizes are positive constants, in metres: `box(lx, ly, lz)`, `sphere(r)`, \
         `cylinder(r, h)`, `capsule(r, h)` with `h >= 2 r`. A negative size describes no body at \
         all, so every collision check about it would hold for the wrong reason; a size that \
         reads the state is not a shape (a robot that moves is placed by `at pose(...)`, whose \
         arguments may read its state). Write the size as a positive number or constant.";
    FootprintMissesBody = "E0512", "a footprint may not contain the robot's body",
        "Sec 3.1: a motion primitive's footprint FP is the space the robot may occupy while it \
         runs, so it must contain the robot's geometry geom(p) at every state the guarantee \
         allows (Fig 3 [TRAJ-STEP]); every collision check trusts it. mochi checks this for every \
         primitive the protocol runs whose kind has a `geometry:`, for every argument, start \
         state its precondition and the invariant allow, and time in its duration. The \
         counterexample is a point of the body (in the robot's own frame, metres) outside the \
         footprint, the time and the state that put it there. Widen the footprint, or write \
         `footprint: geometry;` (the body itself, which contains it by definition).";
    JointWithoutState = "E0513", "a urdf joint has no state variable",
        "A robot whose `geometry:` is a URDF moves its links by its joints, and mochi reads each \
         movable joint's value from the kind's state variable of the same name (Sec 3.1: the \
         state X determines geom(p)). A movable joint (revolute, continuous, prismatic; not \
         fixed, not a mimic joint, which follows another) with no real state variable of its \
         name would leave the robot's shape undetermined. Declare one real state variable per \
         movable joint, named exactly as in the URDF.";
    ObstacleHit = "E0510", "a footprint may meet a static obstacle",
        "A system's obstacles (`obstacle Name { geometry: ...; at: pose(...); }`) are there at \
         every time, whatever the protocol does. Every primitive a joint motion runs is checked \
         against every obstacle, like the parts of the motion against each other ([AGCOMP], Sec \
         3.4): its footprint, at every time its guarantee allows, must not contain a point of the \
         obstacle. The counterexample is a point of the world (x, y, z, in metres) and a time \
         (seconds since the motion started) at which the footprint reaches into the obstacle, \
         with the state that puts it there. Change the motion's target or the participant's \
         pose, or tighten the footprint if it is larger than the robot needs.";
    UrdfInvalid = "E0501", "a urdf file cannot be read as a robot description",
        "A robot's geometry names a URDF file that is not a well-formed robot description: the XML \
         is malformed, an element lacks a required attribute (a `<link>` or `<joint>` without \
         `name`, a `<joint>` without `<parent>` or `<child>`), or an attribute that must hold numbers \
         does not (`xyz=\"0 0 0.1\"`, `rpy`, `size`, `radius`, `length`, `scale`, `<limit \
         lower upper>`, a joint `<axis>` that is zero). The diagnostic points into the URDF file at the \
         offending element or attribute. A URDF is also refused, before it is parsed, when its \
         elements nest deeper than 128 levels, an element has more than 64 attributes, or it \
         declares more than 64 XML namespaces: real URDFs stay far below, and the XML parsers \
         are not linear beyond (a downloaded file could make mochi run for minutes). A common \
         cause is a file generated by xacro whose \
         substitutions were never expanded (`$(optenv ...)`, `${...}`): expand it with `xacro` \
         (or write the values) and point the robot at the result.";
    GeometryFileMissing = "E0502", "a urdf or mesh file cannot be found or read",
        "A robot names a URDF file, or a URDF's `<collision>` names a `<mesh filename=...>`, that \
         cannot be read: it does not exist, is not a regular file, or is larger than 64 MiB. \
         `package://PKG/rest` is looked up in every folder above the URDF's own that contains a \
         folder `PKG` (the package root), `file:///abs` is absolute, and a plain path is relative to \
         the URDF's folder. The message lists where mochi looked.";
    MeshUnreadable = "E0503", "a collision mesh cannot be used",
        "A collision mesh could not be turned into geometry: its format is not supported (mochi \
         reads STL, binary or ASCII, and Wavefront OBJ; COLLADA `.dae` is used by URDFs for visual \
         meshes, which mochi ignores, but not for collision), the file is malformed, or it holds no \
         vertex. Convert the mesh to STL or OBJ (e.g. with MeshLab or Blender) and name that file in \
         the `<collision>` element. A mesh stands for the convex hull of its vertices (a sound \
         over-approximation for proving clearance).";
    JointUnsupported = "E0504", "a urdf joint type is not supported",
        "mochi's kinematics handles `revolute`, `continuous`, `prismatic` and `fixed` joints, each \
         with one joint variable (a state variable of the robot named after the joint). `floating`, \
         `planar` (and SDF-style `spherical`) joints have several degrees of freedom: describe such a \
         robot's base by its participant's pose (`at:`) or by mounting it on a carrier, and make the \
         joint `fixed` in the URDF.";
    UrdfNotATree = "E0505", "a urdf's links do not form one tree",
        "A URDF describes a kinematic tree: every joint connects a parent link to a child link that \
         both exist, a link is the child of at most one joint, link and joint names are unique, and \
         exactly one link (the root) is no joint's child. The diagnostic names what is wrong: a URDF \
         without links, a joint naming an unknown link, a link with two parents, two roots, or a \
         cycle of joints.";
    ShapeInvalid = "E0506", "a shape has a size that is not a positive finite number",
        "A box's lengths, a sphere's, cylinder's or capsule's radius and height (in a robot's body \
         or a URDF `<collision>`), and a mesh's `scale` must be finite and positive (a capsule's \
         height at least twice its radius in mochi's convention, where the height is overall). A \
         zero or negative size describes no solid, and a mirrored mesh is better mirrored in its \
         file.";
    MimicInvalid = "E0507", "a urdf mimic joint does not name a joint it can follow",
        "`<mimic joint=\"J\" multiplier=\"m\" offset=\"o\"/>` makes a joint's value `m * J + o`; \
         mochi supports it (the joint then has no state variable of its own). `J` must be another \
         movable joint of the same URDF, and mimics must not follow each other in a cycle.";
    UrdfTooLarge = "E0530", "a urdf robot reaches farther than mochi's bound",
        "mochi computes a URDF robot's poses and distances in 64-bit floating point, and bounds \
         the robot's size so that these never overflow (an overflowing pose is NaN, which no \
         geometric check may use): every point of every link's collision geometry must be within \
         1000 km (1e6 m) of the root link's origin in every configuration within the joint \
         limits. The reach is measured along each link's chain: the lengths of the joint origins' \
         `xyz`, each prismatic joint's largest travel, and the size of the link's collision \
         solids. The diagnostic points at the joint origin (or link) where the reach first \
         exceeds the bound. A URDF in millimetres without a mesh `scale` is 1000 times too \
         large, but still within the bound; a reach beyond it is a broken file.";
    MotionPrecondition = "E0708", "a motion's precondition may not hold in the process",
        "[T-MOTION] (Table 1): when a process starts a motion, what it knows (Σ: its initial state, \
         the postconditions of its earlier motions, the refinements of values it received, the \
         conditions of enclosing `if`s) must imply the primitive's precondition. The counterexample \
         is a state allowed by Σ in which the precondition is false.";
    SendPredicate = "E0709", "a send may violate its guard or refinement",
        "[T-OUT] (Table 1): a process may send `q!l(e)` only when what it knows implies the \
         message's guard and the refinement of each payload field, with the values sent. The \
         counterexample shows a state allowed by what it knows in which they are false. Send other \
         values, or establish the condition first.";
    InitialCollision = "E0710", "participants may collide in their initial states",
        "[T-SESS] (Table 1) requires the initial states to be collision free. mochi places each \
         participant by the footprint of its first motion at time 0 (a footprint contains the robot, \
         Fig 3 [TRAJ-STEP]) in its initial state, and checks those are pairwise disjoint. The \
         counterexample is a point in both. Move a participant's pose or change its `init`.";
    SubtypePredicate = "E0711", "a predicate of a subtype is weaker than its super type's",
        "[SUB-OUT] and [SUB-IN] (Fig 5): where a written `local R = T;` is checked as a subtype of \
         the projection onto `R` ([T-SUB], Table 1), each send's guard and payload refinement in `T` \
         must imply the projection's (a process of type `T` promises at least as much), and each \
         reception's refinement in the projection must imply `T`'s (the process assumes no more than \
         it is sent). The implication must hold for every value and state; the counterexample is \
         one where it fails. A process's own sends and receptions are checked against its type \
         directly (E0709).";
    ProcessRecInit = "E0712", "a process loop's initial value breaks its parameter's refinement",
        "[T-REC] with parameters (DATUM): a process loop `mu x(k: S {P} = e). P` may assume P of k \
         in its body, so P must hold of e under what the process knows when it enters the loop. \
         The counterexample is a state the process may be in there where P[e/k] is false.";
    ProcessRecJump = "E0713", "a process jump breaks its loop parameter's refinement",
        "[T-VAR] with parameters (DATUM): at `x(a)` the arguments become the loop's parameters, \
         whose refinement P the body assumes, so P[a/k] must hold under what the process knows at \
         the jump. The counterexample is such a state where it fails.";
    ProcessRecArgs = "E0714", "a process loop's parameters disagree with its type's",
        "When a process enters or repeats its loop where its local type enters or repeats a \
         parameterised loop with as many parameters, the process's parameters stand for the type's \
         (positionally): their initial values and the arguments of each jump must be equal to the \
         type's, evaluated with what the process knows (values it sent and received). This is how \
         guards and refinements that read the type's parameters are checked in the process. The \
         counterexample is a state where the process passes a different value than its type.";
    ObservedInProcess = "E0715", "a process typed against a protocol with observed values: not supported yet",
        "Processes are typed against their local types (Table 1), but the typing rules do not yet \
         know observed state: a guard of the local type that reads a stream's latest value would \
         need the process to read the same snapshot, which the process language cannot express \
         yet. The protocol is still checked as a protocol (well-formedness, total choice, progress, \
         termination and knowledge over fresh snapshots). Remove the `process` items to check the \
         protocol alone, or type the processes against a protocol without `stream` reads (send the \
         reading in a payload field and guard on that field).";
    MonitorNotVerified = "E0801", "a protocol that is not verified cannot be monitored",
        "`mochi monitor`, `mochi proxy` and `mochi mission` enforce a protocol's guards and \
         refinements on real MAVLink traffic, and what they enforce is what the static checks \
         assumed when they proved the protocol: that every message is its sender's obligation, \
         that a choice is total, that every loop ends. For a protocol the checks rejected or could \
         not decide, those assumptions are not proved, and a monitor that accepts its runs would \
         accept runs of a wrong protocol. The diagnostic points at the protocol's first error (or \
         undecided obligation), which is shown above it. Run `mochi check FILE`, fix what it reports \
         (or give it more time: `--timeout`), and monitor the verified protocol.";
    MonitorUnsupported = "E0802", "a construct the run-time monitor cannot run",
        "The monitor compiles a verified MAVLink protocol into an automaton over the messages of \
         one stream. Some constructs have no run-time meaning there: a joint motion or a parallel \
         composition `*` (the monitor sees MAVLink messages, not motions), a program without a \
         `dialect` (no wire format to decode), more than 64 participants, a loop that can jump back \
         without any message (it would spin without input), and a value that is not held in a \
         register (a name the monitor cannot evaluate). The diagnostic names the construct and \
         points at it. Monitor a MAVLink protocol (`dialect common;`, messages only), and write a \
         loop so that every path through its body sends a message.";
    Undecided = "U0001", "proof obligations undecided",
        "Some checks reduce to predicate validity (total choice, [AGCOMP] compatibility, full \
         separation of footprints, refinement and typing side conditions). When a query could not \
         be decided — no solver in this build, a timeout, or an unsupported theory — the check is \
         reported as unknown and the verdict is `unknown` (exit code 3), never `verified`.";
}
