//! Plug-ins: what a paper (or a user's crate) adds to the paper-free core, as its own crate
//! (papers/<name>/), and how binaries are composed from the core and plug-ins (bins/src/lib.rs:
//! one line per plug-in).
//!
//! A plug-in is a type that implements [`Plugin`] (this crate: its scenario sections and its
//! behaviours), `world::mission::Missions` (its world missions) and
//! `orchestrator::Reports` (its experiment reports), each with nothing as the default. A
//! tuple of plug-ins is a plug-in (the first that knows a behaviour runs it).
//!
//! Sections: a plug-in's section is a top-level table of the scenario file (`[search]`), a
//! [`Section`] type. A scenario holds every section it was given ([`Sections`]): typed as
//! soon as the section's type is known (registered by the binary's composition, [`register`],
//! or asked for by its type, `Scenario::section`), kept as TOML until then; an agent program
//! that knows no plug-in reads a scenario with any section. What is registered decides how a
//! resolved scenario is written (sections in registration order, defaults included) and what
//! `validate_sections` refuses (a section nobody registered).

use serde::de::DeserializeOwned;
use serde::Serialize;
use std::any::{Any, TypeId};
use std::fmt::Debug;
use std::sync::{LazyLock, Mutex, OnceLock, RwLock};

use crate::scenario::{Check, ConfigError, Scenario};
use crate::Behaviour;

/// A plug-in's scenario section: the top-level table [`Section::NAME`] of a scenario file.
pub trait Section:
    Serialize + DeserializeOwned + Clone + Debug + PartialEq + Send + Sync + 'static
{
    /// The table's name (`search` for `[search]`).
    const NAME: &'static str;
    /// The section's defaults as TOML (the table's keys, no header): a file's section is
    /// merged over them, so it needs to hold only what it changes. None: a file that has the
    /// section writes all of it.
    const DEFAULTS: Option<&'static str> = None;
    /// The section a scenario without it has (None: it has none).
    fn absent() -> Option<Self> {
        None
    }
    /// Whether a resolved scenario leaves it out (an empty section reads back the same).
    fn is_empty(&self) -> bool {
        false
    }
}

/// A [`Section`] of any type (what [`Sections`] holds).
pub trait AnySection: Any + Debug + Send + Sync {
    fn name(&self) -> &'static str;
    fn clone_box(&self) -> Box<dyn AnySection>;
    /// As TOML (comparisons; the section's keys in the type's order).
    fn to_value(&self) -> toml::Value;
    fn is_empty(&self) -> bool;
    fn as_any(&self) -> &dyn Any;
    fn as_any_mut(&mut self) -> &mut dyn Any;
    /// For writing the scenario with the section's own field order.
    fn as_serialize(&self) -> &dyn erased_serde::Serialize;
}

impl<S: Section> AnySection for S {
    fn name(&self) -> &'static str {
        S::NAME
    }
    fn clone_box(&self) -> Box<dyn AnySection> {
        Box::new(self.clone())
    }
    fn to_value(&self) -> toml::Value {
        toml::Value::try_from(self).unwrap_or(toml::Value::Table(toml::Table::new()))
    }
    fn is_empty(&self) -> bool {
        Section::is_empty(self)
    }
    fn as_any(&self) -> &dyn Any {
        self
    }
    fn as_any_mut(&mut self) -> &mut dyn Any {
        self
    }
    fn as_serialize(&self) -> &dyn erased_serde::Serialize {
        self
    }
}

/// A section's parse error: the key path inside the section and the message.
pub type SectionError = serde_path_to_error::Error<toml::de::Error>;

/// How the core reads, defaults and writes one registered section type.
#[derive(Clone, Copy)]
pub struct SectionEntry {
    pub name: &'static str,
    parse: fn(toml::Value) -> Result<Box<dyn AnySection>, SectionError>,
    absent: fn() -> Option<Box<dyn AnySection>>,
}

impl SectionEntry {
    /// The entry of section type `S`.
    pub const fn of<S: Section>() -> SectionEntry {
        SectionEntry {
            name: S::NAME,
            parse: |v| parse_section::<S>(v).map(|s| Box::new(s) as Box<dyn AnySection>),
            absent: || S::absent().map(|s| Box::new(s) as Box<dyn AnySection>),
        }
    }
}

/// `v` merged over `S::DEFAULTS`, as `S`.
fn parse_section<S: Section>(v: toml::Value) -> Result<S, SectionError> {
    let v = match (S::DEFAULTS, v) {
        (Some(d), toml::Value::Table(t)) => {
            let mut base: toml::Table = d
                .parse()
                .unwrap_or_else(|e| panic!("the defaults of [{}] parse: {e}", S::NAME));
            crate::scenario::merge(&mut base, t);
            toml::Value::Table(base)
        }
        (_, v) => v,
    };
    serde_path_to_error::deserialize(v)
}

/// The sections every binary of this process knows, in the order a resolved scenario lists
/// them (the composition's order); until a binary registers its own, the papers' sections
/// still in this crate (issue 40 moves them to papers/).
static REGISTRY: LazyLock<RwLock<Registry>> = LazyLock::new(|| {
    RwLock::new(Registry {
        composed: false,
        entries: crate::sections::builtin_entries(),
    })
});

struct Registry {
    /// Set by the first [`register`]: the defaults are then replaced, not added to.
    composed: bool,
    entries: Vec<SectionEntry>,
}

/// Registers section types (those not yet registered, after those that are); the first call
/// replaces the defaults (a composed binary says every section it knows, in order).
pub fn register(entries: &[SectionEntry]) {
    let mut r = REGISTRY.write().unwrap_or_else(|e| e.into_inner());
    if !r.composed {
        r.composed = true;
        r.entries.clear();
    }
    for e in entries {
        if !r.entries.iter().any(|x| x.name == e.name) {
            r.entries.push(*e);
        }
    }
}

/// The registered sections, in order.
pub fn registered() -> Vec<SectionEntry> {
    REGISTRY
        .read()
        .unwrap_or_else(|e| e.into_inner())
        .entries
        .clone()
}

fn entry(name: &str) -> Option<SectionEntry> {
    REGISTRY
        .read()
        .unwrap_or_else(|e| e.into_inner())
        .entries
        .iter()
        .find(|e| e.name == name)
        .copied()
}

/// One section of a scenario: as read (TOML), typed once its type is known.
#[derive(Debug)]
struct Slot {
    name: String,
    /// The file's table (merged over the section's defaults when typed).
    raw: Option<toml::Value>,
    typed: OnceLock<Box<dyn AnySection>>,
}

impl Clone for Slot {
    fn clone(&self) -> Self {
        let typed = OnceLock::new();
        if let Some(t) = self.typed.get() {
            let _ = typed.set(t.clone_box());
        }
        Slot {
            name: self.name.clone(),
            raw: self.raw.clone(),
            typed,
        }
    }
}

impl Slot {
    fn typed(name: &str, s: Box<dyn AnySection>) -> Slot {
        let typed = OnceLock::new();
        let _ = typed.set(s);
        Slot {
            name: name.to_string(),
            raw: None,
            typed,
        }
    }

    /// As TOML (the typed section's; else the file's, read as its type if that is
    /// registered, so a section read before its type was registered compares equal to the same
    /// section read after).
    fn value(&self) -> toml::Value {
        match (self.typed.get(), &self.raw) {
            (Some(t), _) => t.to_value(),
            (None, Some(r)) => entry(&self.name)
                .and_then(|e| (e.parse)(r.clone()).ok())
                .map_or_else(|| r.clone(), |t| t.to_value()),
            (None, None) => toml::Value::Table(toml::Table::new()),
        }
    }

    fn get<S: Section>(&self) -> &S {
        let t = self.typed.get_or_init(|| {
            let raw = self
                .raw
                .clone()
                .unwrap_or(toml::Value::Table(toml::Table::new()));
            match parse_section::<S>(raw) {
                Ok(s) => Box::new(s),
                Err(e) => panic!(
                    "[{}] does not read as its type (the scenario was not validated): {}: {}",
                    S::NAME,
                    e.path(),
                    e.inner()
                ),
            }
        });
        t.as_any()
            .downcast_ref::<S>()
            .unwrap_or_else(|| panic!("[{}] holds another type than asked", S::NAME))
    }
}

/// A scenario's plug-in sections, in the order they are written.
#[derive(Debug, Clone, Default)]
pub struct Sections {
    slots: Vec<Slot>,
}

impl PartialEq for Sections {
    fn eq(&self, other: &Self) -> bool {
        self.slots.len() == other.slots.len()
            && self
                .slots
                .iter()
                .zip(&other.slots)
                .all(|(a, b)| a.name == b.name && a.value() == b.value())
    }
}

/// One default per section type asked for while the scenario has none (made once, kept).
fn absent_of<S: Section>() -> Option<&'static S> {
    static ABSENT: Mutex<Vec<(TypeId, Option<&'static (dyn Any + Send + Sync)>)>> =
        Mutex::new(Vec::new());
    let mut a = ABSENT.lock().unwrap_or_else(|e| e.into_inner());
    let id = TypeId::of::<S>();
    let found = match a.iter().find(|(t, _)| *t == id) {
        Some((_, v)) => *v,
        None => {
            let v: Option<&'static (dyn Any + Send + Sync)> =
                S::absent().map(|s| &*Box::leak(Box::new(s)) as &(dyn Any + Send + Sync));
            a.push((id, v));
            v
        }
    };
    found.and_then(|v| v.downcast_ref::<S>())
}

impl Sections {
    /// The sections of a scenario file's top-level tables `tables` (the core's removed):
    /// registered ones typed (a parse error names `name.key`), in registration order, with
    /// the registered sections the file does not have that exist anyway ([`Section::absent`]);
    /// then the others as read, by name.
    pub(crate) fn read(
        mut tables: toml::Table,
    ) -> Result<Sections, (String, String, serde_path_to_error::Path)> {
        let mut slots = Vec::new();
        for e in registered() {
            match tables.remove(e.name) {
                Some(v) => match (e.parse)(v) {
                    Ok(s) => slots.push(Slot::typed(e.name, s)),
                    Err(err) => {
                        return Err((e.name.to_string(), err.inner().message().to_string(), {
                            err.path().clone()
                        }))
                    }
                },
                None => {
                    if let Some(s) = (e.absent)() {
                        slots.push(Slot::typed(e.name, s));
                    }
                }
            }
        }
        for (name, v) in tables {
            slots.push(Slot {
                name,
                raw: Some(v),
                typed: OnceLock::new(),
            });
        }
        Ok(Sections { slots })
    }

    /// Section `S`: the scenario's, or the one a scenario without it has (None: none).
    pub fn get<S: Section>(&self) -> Option<&S> {
        match self.slots.iter().find(|s| s.name == S::NAME) {
            Some(slot) => Some(slot.get::<S>()),
            None => absent_of::<S>(),
        }
    }

    /// Section `S` to change (made from its [`Section::absent`] if the scenario has none;
    /// None if there is no such default: [`Sections::set`] it).
    pub fn get_mut<S: Section>(&mut self) -> Option<&mut S> {
        let i = match self.slots.iter().position(|s| s.name == S::NAME) {
            Some(i) => i,
            None => {
                let s = S::absent()?;
                self.set(s);
                self.slots.iter().position(|s| s.name == S::NAME)?
            }
        };
        self.slots[i].get::<S>();
        let slot = &mut self.slots[i];
        slot.raw = None;
        slot.typed
            .get_mut()
            .and_then(|t| t.as_any_mut().downcast_mut::<S>())
    }

    /// Sets section `S` (in its registered place; an unregistered one goes last).
    pub fn set<S: Section>(&mut self, s: S) {
        let slot = Slot::typed(S::NAME, Box::new(s));
        if let Some(i) = self.slots.iter().position(|x| x.name == S::NAME) {
            self.slots[i] = slot;
            return;
        }
        let order: Vec<&str> = registered().iter().map(|e| e.name).collect();
        let rank = |n: &str| order.iter().position(|o| *o == n).unwrap_or(usize::MAX);
        let at = self
            .slots
            .iter()
            .position(|x| rank(&x.name) > rank(S::NAME))
            .unwrap_or(self.slots.len());
        self.slots.insert(at, slot);
    }

    /// Removes section `S`.
    pub fn remove<S: Section>(&mut self) {
        self.slots.retain(|s| s.name != S::NAME);
    }

    /// The names of the sections present (written or defaulted), in order.
    pub fn names(&self) -> impl Iterator<Item = &str> {
        self.slots.iter().map(|s| s.name.as_str())
    }

    /// The sections a scenario file set: present, not empty, and not as `default` (the
    /// embedded default scenario's) has them (so a resolved scenario.toml, which lists every
    /// section, reads back as its run wrote it).
    pub fn set_apart_from(&self, default: &Sections) -> Vec<String> {
        self.slots
            .iter()
            .filter(|s| {
                if s.typed.get().is_some_and(|t| t.is_empty()) {
                    return false;
                }
                match default.slots.iter().find(|d| d.name == s.name) {
                    Some(d) => d.value() != s.value(),
                    None => true,
                }
            })
            .map(|s| s.name.clone())
            .collect()
    }

    /// The sections nobody registered (a binary's validation refuses them).
    pub fn unknown(&self) -> Vec<&str> {
        self.slots
            .iter()
            .filter(|s| entry(&s.name).is_none())
            .map(|s| s.name.as_str())
            .collect()
    }

    /// Writes the sections as fields of the scenario's table (left out: empty ones).
    pub(crate) fn serialize_into<M: serde::ser::SerializeStruct>(
        &self,
        st: &mut M,
    ) -> Result<(), M::Error> {
        for s in &self.slots {
            match (s.typed.get(), &s.raw) {
                (Some(t), _) if t.is_empty() => {}
                (Some(t), _) => st.serialize_field(t.name(), t.as_serialize())?,
                (None, Some(r)) => {
                    // An unregistered section (an agent program's copy): its name is not
                    // 'static, and nobody writes such a scenario but tests.
                    let name: &'static str = Box::leak(s.name.clone().into_boxed_str());
                    st.serialize_field(name, r)?
                }
                (None, None) => {}
            }
        }
        Ok(())
    }

    /// How many sections are written.
    pub(crate) fn written(&self) -> usize {
        self.slots
            .iter()
            .filter(|s| !s.typed.get().is_some_and(|t| t.is_empty()))
            .count()
    }
}

/// Something to do with the scenario's behaviour type (run it in an agent process, or
/// in-process).
pub trait BehaviourVisitor {
    type Out;
    fn visit<B: Behaviour + Send + 'static>(self, make: &dyn Fn(u32) -> B) -> Self::Out
    where
        B::Msg: Send + Sync;
}

/// What the core knows of one behaviour of a plug-in (by name).
#[derive(Clone, Copy)]
pub struct BehaviourInfo {
    /// `run.behaviour`'s value.
    pub name: &'static str,
    /// The scenario sections it reads (a run refuses any other behaviour's or mission's).
    pub sections: &'static [&'static str],
    /// Checks its sections against the scenario.
    pub validate: fn(&Scenario, &Check) -> Result<(), ConfigError>,
    /// Writes every parameter of the behaviour into the scenario, defaults included.
    pub resolve: fn(&mut Scenario) -> Result<(), ConfigError>,
}

/// A plug-in's agent side: its sections and behaviours. Implemented by each plug-in (a unit
/// type) and by tuples of plug-ins (the composition: bins/src/lib.rs).
pub trait Plugin {
    /// Its scenario sections, in the order a resolved scenario lists them.
    fn sections() -> Vec<SectionEntry> {
        Vec::new()
    }
    /// Its behaviours.
    fn behaviours() -> Vec<BehaviourInfo> {
        Vec::new()
    }
    /// Calls `v` with the constructor of the scenario's behaviour if it is one of this
    /// plug-in's (the scenario validated), else gives `v` back.
    fn dispatch<V: BehaviourVisitor>(_sc: &Scenario, v: V) -> Result<V::Out, V> {
        Err(v)
    }
}

/// Registers the sections of plug-in `P` (the first thing a composed binary does).
pub fn register_plugin<P: Plugin>() {
    register(&P::sections());
}

/// The behaviour `name` of `P`.
pub fn behaviour<P: Plugin>(name: &str) -> Option<BehaviourInfo> {
    P::behaviours().into_iter().find(|b| b.name == name)
}

/// The names of every behaviour of `P`.
pub fn behaviour_names<P: Plugin>() -> Vec<&'static str> {
    P::behaviours().iter().map(|b| b.name).collect()
}

impl Plugin for () {}

macro_rules! tuple_plugin {
    ($($p:ident),+) => {
        impl<$($p: Plugin),+> Plugin for ($($p,)+) {
            fn sections() -> Vec<SectionEntry> {
                let mut v = Vec::new();
                $(v.extend($p::sections());)+
                v
            }
            fn behaviours() -> Vec<BehaviourInfo> {
                let mut v = Vec::new();
                $(v.extend($p::behaviours());)+
                v
            }
            fn dispatch<V: BehaviourVisitor>(sc: &Scenario, v: V) -> Result<V::Out, V> {
                $(let v = match $p::dispatch(sc, v) {
                    Ok(out) => return Ok(out),
                    Err(v) => v,
                };)+
                Err(v)
            }
        }
    };
}

tuple_plugin!(A);
tuple_plugin!(A, B);
tuple_plugin!(A, B, C);
tuple_plugin!(A, B, C, D);
tuple_plugin!(A, B, C, D, E);
tuple_plugin!(A, B, C, D, E, F);
tuple_plugin!(A, B, C, D, E, F, G);
tuple_plugin!(A, B, C, D, E, F, G, H);

#[cfg(test)]
mod tests {
    use super::*;
    use serde::Deserialize;

    /// A plug-in's section of a test (never registered: registering would replace this
    /// process's defaults under the other tests).
    #[derive(Serialize, Deserialize, Clone, Debug, PartialEq)]
    #[serde(deny_unknown_fields)]
    struct Demo {
        a: u32,
        b: String,
    }

    impl Section for Demo {
        const NAME: &'static str = "plugin_demo";
        const DEFAULTS: Option<&'static str> = Some("a = 1\nb = \"x\"");
    }

    /// Absent unless written, no defaults.
    #[derive(Serialize, Deserialize, Clone, Debug, PartialEq)]
    struct Bare {
        n: i64,
    }

    impl Section for Bare {
        const NAME: &'static str = "plugin_bare";
    }

    #[test]
    fn an_unregistered_section_is_kept_and_typed_when_asked_for() {
        let sc = Scenario::parse("[plugin_demo]\na = 5\n", "t.toml").unwrap();
        // Kept as written until its type asks: the defaults merged under it then.
        assert!(sc.sections.unknown().contains(&"plugin_demo"));
        let d = sc.section::<Demo>().unwrap();
        assert_eq!((d.a, d.b.as_str()), (5, "x"));
        assert!(sc.section::<Bare>().is_none());
        // Written back as a table of the scenario, after the core's sections.
        let text = sc.to_toml();
        let faults = text.find("[faults]").unwrap();
        let demo = text.find("[plugin_demo]").expect(&text);
        assert!(demo > faults, "{text}");
        let again = Scenario::parse(&text, "resolved.toml").unwrap();
        assert_eq!(again.section::<Demo>(), Some(d));
    }

    #[test]
    fn sections_are_set_changed_and_removed_by_type() {
        let mut sc = Scenario::default();
        assert!(
            sc.sections.get_mut::<Bare>().is_none(),
            "no default to make"
        );
        sc.sections.set(Bare { n: 3 });
        sc.sections.get_mut::<Bare>().unwrap().n += 1;
        assert_eq!(sc.section::<Bare>(), Some(&Bare { n: 4 }));
        assert!(sc.sections_set().contains(&"plugin_bare".to_string()));
        let back = Scenario::parse(&sc.to_toml(), "resolved.toml").unwrap();
        assert_eq!(back.section::<Bare>(), Some(&Bare { n: 4 }));
        sc.sections.remove::<Bare>();
        assert!(sc.section::<Bare>().is_none());
        assert!(!sc.to_toml().contains("plugin_bare"));
    }

    #[test]
    fn a_section_that_does_not_read_as_its_type_panics_naming_it() {
        let sc = Scenario::parse("[plugin_bare]\nn = \"three\"\n", "t.toml").unwrap();
        let e = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
            sc.section::<Bare>().cloned()
        }))
        .unwrap_err();
        let m = e.downcast_ref::<String>().cloned().unwrap_or_default();
        assert!(m.contains("[plugin_bare]") && m.contains('n'), "{m}");
    }
}
