//! Message classes (§3.2 of the report).

use std::fmt;

use serde::{Deserialize, Serialize};

/// What kind of message an envelope carries, which decides how central treats it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[non_exhaustive]
pub enum Class {
    /// A request for information: blocks its sender until the handler's [`Class::Reply`] (or a
    /// [`Class::Failure`] or central's [`Class::Error`]) comes back.
    Query,
    /// A task to plan: non-blocking; becomes a task-tree node under the sender's current node and
    /// is ended by its handler with [`Class::Success`] or [`Class::Failure`].
    Goal,
    /// A task to execute: like a goal, typically a leaf of the task tree.
    Command,
    /// One-way information: delivered to its handler, nothing comes back.
    Inform,
    /// Raised by a handler in the context of its task node; central routes it to the nearest
    /// registered exception handler up the task tree.
    Exception,
    /// A handler's answer to a query (`correlation` names the query).
    Reply,
    /// A handler ends a goal, command or exception successfully (`correlation` names it).
    Success,
    /// A handler ends a goal, command, query or exception with a failure
    /// (`correlation` names it; data is a [`crate::Failure`]).
    Failure,
    /// Central's answer when it cannot route or accept a message (`correlation` names it; data is
    /// a [`crate::RouteError`]).
    Error,
    /// Control traffic between a module and central: connection, registration, inspection,
    /// constraints, kills. Message names start with `tca.`.
    Control,
}

impl Class {
    /// Classes a module registers handlers for.
    pub const HANDLED: [Class; 5] = [
        Class::Query,
        Class::Goal,
        Class::Command,
        Class::Inform,
        Class::Exception,
    ];

    /// True for goals and commands: the classes that become task-tree nodes.
    pub fn is_task(self) -> bool {
        matches!(self, Class::Goal | Class::Command)
    }

    /// True for goals, commands and exceptions: the classes whose handlers a module runs in
    /// turn, each starting (in simulated time) no earlier than the previous one ended.
    /// Queries and informs are answered as of the time they were sent.
    pub fn runs_in_turn(self) -> bool {
        matches!(self, Class::Goal | Class::Command | Class::Exception)
    }

    /// True for classes routed by name to a registered handler.
    pub fn is_handled(self) -> bool {
        Self::HANDLED.contains(&self)
    }

    /// Lower-case name, as shown in logs and accepted by `--class`.
    pub fn as_str(self) -> &'static str {
        match self {
            Class::Query => "query",
            Class::Goal => "goal",
            Class::Command => "command",
            Class::Inform => "inform",
            Class::Exception => "exception",
            Class::Reply => "reply",
            Class::Success => "success",
            Class::Failure => "failure",
            Class::Error => "error",
            Class::Control => "control",
        }
    }

    /// All classes.
    pub const ALL: [Class; 10] = [
        Class::Query,
        Class::Goal,
        Class::Command,
        Class::Inform,
        Class::Exception,
        Class::Reply,
        Class::Success,
        Class::Failure,
        Class::Error,
        Class::Control,
    ];
}

impl fmt::Display for Class {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.as_str())
    }
}

impl std::str::FromStr for Class {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        Class::ALL
            .into_iter()
            .find(|c| c.as_str().eq_ignore_ascii_case(s))
            .ok_or_else(|| {
                let all: Vec<&str> = Class::ALL.iter().map(|c| c.as_str()).collect();
                format!("unknown class {s:?}; expected one of {}", all.join(", "))
            })
    }
}
