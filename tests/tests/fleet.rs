//! The farm's store on PostgreSQL (issue 40) against a real server: it keeps what the file store
//! keeps, call for call, and its schema is migrated once however many coordinators open it.
//! Skipped, saying so, without `RESTAURO_TEST_POSTGRES` (see `restauro_tests::fleet`).

use restauro_farm::store::Store;

type Seen = Vec<String>;

/// The same calls on `store`, and what each answered, in words.
fn exercise(store: &Store) -> Seen {
    let mut seen = Vec::new();
    let mut say = |what: &str, value: String| seen.push(format!("{what}: {value}"));
    let (secret, first) = store.begin_run([7; 32]).unwrap();
    let (again, second) = store.begin_run([9; 32]).unwrap();
    say("epochs", format!("{first} {second}, secret kept {}", secret == again));
    store.put_job("b", b"record b").unwrap();
    store.put_job("a", b"record a").unwrap();
    store.put_job("a", b"record a, later").unwrap();
    say("jobs", format!("{:?}", store.jobs().unwrap()));
    store.put_revision("scene", 2, b"two").unwrap();
    store.put_revision("scene", 1, b"one").unwrap();
    say("revisions", format!("{:?}", store.revisions().unwrap()));
    // A batch with a tile twice: its last bytes stand.
    let tiles: Vec<(&str, u32, &[u8])> =
        vec![("a", 5, b"x"), ("a", 1, b"y"), ("b", 0, b"z"), ("a", 5, b"x2"), ("a", 9, b"w")];
    store.put_tiles(&tiles).unwrap();
    say("finished a", format!("{:?}", store.finished_tiles("a").unwrap()));
    say("tile a 5", format!("{:?}", store.tile("a", 5).unwrap()));
    say("tile a 2", format!("{:?}", store.tile("a", 2).unwrap()));
    store.put_disputed("a", 1, b"other").unwrap();
    say("disputed", format!("{:?}", store.disputed("a", 1).unwrap()));
    store.remove_tile_list("a", &[1]).unwrap();
    say(
        "after list",
        format!("{:?} {:?}", store.finished_tiles("a").unwrap(), store.disputed("a", 1).unwrap()),
    );
    store.remove_tile_range("a", 5..9).unwrap();
    say("after range", format!("{:?}", store.finished_tiles("a").unwrap()));
    store.put_disputed("b", 0, b"d").unwrap();
    store.remove_tiles("b").unwrap();
    say(
        "after removal",
        format!("{:?} {:?}", store.finished_tiles("b").unwrap(), store.disputed("b", 0).unwrap()),
    );
    store.put_quarantine("00000000000000ff", b"{}").unwrap();
    say("quarantine", format!("{:?}", store.quarantine().unwrap()));
    say("problem", format!("{:?}", store.problem()));
    seen
}

#[test]
fn the_postgres_store_keeps_what_the_file_store_keeps() {
    let Some(url) = restauro_tests::fleet::database("store") else { return };
    let dir = tempfile::tempdir().unwrap();
    let file = exercise(&Store::open(&dir.path().join("store.redb")).unwrap());
    let postgres = exercise(&Store::connect(&url).unwrap());
    assert_eq!(postgres, file);
    // Opened again (a second coordinator, a restart): the schema is not migrated twice, and
    // what was kept is there.
    let reopened = Store::connect(&url).unwrap();
    assert_eq!(reopened.jobs().unwrap().len(), 2);
    assert_eq!(reopened.begin_run([0; 32]).unwrap().1, 3);
}

#[test]
fn a_database_that_is_not_there_is_refused_naming_it_without_the_password() {
    let Some(url) = restauro_tests::fleet::database("absent") else { return };
    let (server, _) = url.rsplit_once('/').unwrap();
    let absent = format!("{server}/no_such_database");
    let Err(e) = Store::connect(&absent) else { panic!("a database that is not there opened") };
    let e = e.to_string();
    assert!(e.contains("no_such_database") && e.contains("does not exist"), "{e}");
    assert!(!e.contains(":restauro@"), "the password is shown: {e}");
}
