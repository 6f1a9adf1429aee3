//! The object store on S3 (`object_store`'s client, over the hyper and rustls the farm already
//! builds: `http`). Endpoint, region and credentials come from the environment, as for any S3
//! client: `AWS_ENDPOINT_URL` (another S3-compatible server), `AWS_REGION`, `AWS_ACCESS_KEY_ID`,
//! `AWS_SECRET_ACCESS_KEY`, `AWS_ALLOW_HTTP=true` for a plain-HTTP endpoint on a private network.

use super::{ObjectsError, Result};
use object_store::path::Path as Key;
use object_store::{ObjectStore, ObjectStoreExt, PutPayload, WriteMultipart};
use std::io::Read as _;
use std::path::Path;

/// Files larger than this go in parts (S3's multipart upload), this large each.
const PART_BYTES: usize = 16 << 20;

pub struct S3Objects {
    /// The URL, for messages.
    url: String,
    store: Box<dyn ObjectStore>,
    prefix: String,
    runtime: crate::blocking::Blocking,
    /// Why puts fail, while they do (a full bucket, a server down).
    problem: crate::problem::Problems,
}

/// A request the server fails (5xx, a dropped connection) is tried again within a few seconds,
/// not object_store's default three minutes: an upload waiting on a full bucket must be
/// refused while its client still waits, and the farm's own loops (assembly) retry for longer.
fn retries() -> object_store::RetryConfig {
    object_store::RetryConfig {
        max_retries: 3,
        retry_timeout: std::time::Duration::from_secs(8),
        ..Default::default()
    }
}

impl S3Objects {
    pub fn open(url: &str) -> Result<S3Objects> {
        let refused = |message: String| ObjectsError::S3 { url: url.to_owned(), message };
        let rest = url.strip_prefix("s3://").ok_or_else(|| {
            refused("give s3://BUCKET[/PREFIX] (the endpoint and credentials in AWS_*)".into())
        })?;
        let (bucket, prefix) = rest.split_once('/').unwrap_or((rest, ""));
        if bucket.is_empty() {
            return Err(refused("no bucket: give s3://BUCKET[/PREFIX]".into()));
        }
        let mut builder = object_store::aws::AmazonS3Builder::from_env()
            .with_bucket_name(bucket)
            .with_http_connector(super::http::Connector)
            .with_retry(retries());
        if let Ok(endpoint) = std::env::var("AWS_ENDPOINT_URL") {
            builder = builder.with_endpoint(endpoint);
        }
        let store = builder.build().map_err(|e| refused(e.to_string()))?;
        let runtime = crate::blocking::Blocking::start("objects-s3")
            .map_err(|e| refused(format!("starting its runtime: {e}")))?;
        let objects = S3Objects {
            url: url.to_owned(),
            store: Box::new(store),
            prefix: prefix.trim_matches('/').to_owned(),
            runtime,
            problem: crate::problem::Problems::of("object store"),
        };
        objects.check()?;
        Ok(objects)
    }

    fn key(&self, key: &str) -> Key {
        match self.prefix.as_str() {
            "" => Key::from(key),
            prefix => Key::from(format!("{prefix}/{key}")),
        }
    }

    fn error(&self, doing: &str, e: impl std::fmt::Display) -> ObjectsError {
        ObjectsError::S3 { url: self.url.clone(), message: format!("{doing}: {e}") }
    }

    /// The bucket answers, and these credentials may write it: a small probe object is put.
    fn check(&self) -> Result<()> {
        let probe = self.key(".restauro-probe");
        let payload = PutPayload::from_static(b"restauro checks it may write here\n");
        self.runtime.run(|| self.store.put(&probe, payload)).map(drop).map_err(|e| {
            self.error(
                "cannot write to the bucket (check AWS_ENDPOINT_URL, the credentials, and that \
                 the bucket exists)",
                e,
            )
        })
    }

    /// Puts a file; a failure is also the object store's problem until puts succeed again.
    pub fn put_file(&self, key: &str, path: &Path) -> Result<()> {
        let put = self.put(key, path);
        match &put {
            Ok(()) => self.problem.succeeded(),
            Err(ObjectsError::S3 { message, .. }) => self.problem.failed(&self.url, message),
        }
        put
    }

    pub fn problem(&self) -> Option<String> {
        self.problem.describe(&self.url)
    }

    fn put(&self, key: &str, path: &Path) -> Result<()> {
        let doing = format!("putting {}", path.display());
        let mut file = std::fs::File::open(path).map_err(|e| self.error(&doing, e))?;
        let size = file.metadata().map_err(|e| self.error(&doing, e))?.len();
        let location = self.key(key);
        if size <= PART_BYTES as u64 {
            let mut bytes = Vec::with_capacity(size as usize);
            file.read_to_end(&mut bytes).map_err(|e| self.error(&doing, e))?;
            let put = self.store.put(&location, PutPayload::from(bytes));
            return self.runtime.run(|| put).map(drop).map_err(|e| self.error(&doing, e));
        }
        self.runtime.run(|| async {
            let upload =
                self.store.put_multipart(&location).await.map_err(|e| self.error(&doing, e))?;
            let mut parts = WriteMultipart::new_with_chunk_size(upload, PART_BYTES);
            let mut buffer = vec![0; PART_BYTES];
            loop {
                let read = file.read(&mut buffer).map_err(|e| self.error(&doing, e))?;
                if read == 0 {
                    break;
                }
                parts.wait_for_capacity(2).await.map_err(|e| self.error(&doing, e))?;
                parts.write(&buffer[..read]);
            }
            parts.finish().await.map(drop).map_err(|e| self.error(&doing, e))
        })
    }

    pub fn fetch(&self, key: &str, path: &Path) -> Result<bool> {
        let doing = format!("fetching {key}");
        let location = self.key(key);
        let partial = path.with_extension(format!("fetching-{}", uuid::Uuid::new_v4().simple()));
        let fetched = self.runtime.run(|| async {
            let got = match self.store.get(&location).await {
                Ok(got) => got,
                Err(object_store::Error::NotFound { .. }) => return Ok(false),
                Err(e) => return Err(self.error(&doing, e)),
            };
            if let Some(dir) = path.parent() {
                std::fs::create_dir_all(dir).map_err(|e| self.error(&doing, e))?;
            }
            let mut file = std::fs::File::create(&partial).map_err(|e| self.error(&doing, e))?;
            let mut stream = got.into_stream();
            use futures_util::StreamExt as _;
            use std::io::Write as _;
            while let Some(chunk) = stream.next().await {
                let chunk = chunk.map_err(|e| self.error(&doing, e))?;
                file.write_all(&chunk).map_err(|e| self.error(&doing, e))?;
            }
            file.sync_all().map_err(|e| self.error(&doing, e))?;
            std::fs::rename(&partial, path).map_err(|e| self.error(&doing, e))?;
            Ok(true)
        });
        if fetched.is_err() {
            let _ = std::fs::remove_file(&partial);
        }
        fetched
    }
}
