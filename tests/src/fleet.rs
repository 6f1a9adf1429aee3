//! The real servers the fleet tests run against (issue 40): a PostgreSQL server, named by
//! `RESTAURO_TEST_POSTGRES` (a URL whose user may create databases; `.ci/run` starts one and
//! sets it). Without it a fleet test says it is skipped and passes, unless
//! `RESTAURO_REQUIRE_FLEET` is set (as CI sets it), when it fails.

/// A fresh database for the test `name` on the test server, as a URL; `None` (the test is
/// skipped, saying so) when there is no server to test against.
pub fn database(name: &str) -> Option<String> {
    let Ok(admin) = std::env::var("RESTAURO_TEST_POSTGRES") else {
        assert!(
            std::env::var_os("RESTAURO_REQUIRE_FLEET").is_none(),
            "RESTAURO_REQUIRE_FLEET is set and RESTAURO_TEST_POSTGRES is not: no PostgreSQL to test {name} against"
        );
        eprintln!(
            "skipped {name}: set RESTAURO_TEST_POSTGRES=postgres://… to test against PostgreSQL"
        );
        return None;
    };
    let db = format!("restauro_{name}_{}", std::process::id());
    let runtime = tokio::runtime::Builder::new_current_thread().enable_all().build().unwrap();
    runtime.block_on(async {
        let (client, connection) = tokio_postgres::connect(&admin, tokio_postgres::NoTls)
            .await
            .unwrap_or_else(|e| panic!("RESTAURO_TEST_POSTGRES={admin}: {e}"));
        tokio::spawn(connection);
        client.batch_execute(&format!("DROP DATABASE IF EXISTS {db} WITH (FORCE)")).await.unwrap();
        client.batch_execute(&format!("CREATE DATABASE {db}")).await.unwrap();
    });
    let (base, query) = admin.split_once('?').map_or((admin.as_str(), None), |(b, q)| (b, Some(q)));
    let server = base.rsplit_once('/').map_or(base, |(server, _)| server);
    Some(match query {
        Some(q) => format!("{server}/{db}?{q}"),
        None => format!("{server}/{db}"),
    })
}
