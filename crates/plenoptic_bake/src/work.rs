//! The work directory: resumable, shardable baking.
//!
//! A bake's rendering is cut into *work items*: one per (base view, time key) range image and
//! one per base view's temporal volume, listed in a canonical order ([`work_items`]). Each
//! finished item is written to `<output>.work/<item>.chunks` (temporary file, fsync, rename),
//! holding its encoded pack chunks. A file that exists is complete. So
//!
//! - `--resume` re-renders only the items without a file;
//! - `--shard i/N` renders the items whose canonical index is `i mod N` (round robin, so the
//!   shards are balanced), and any number of processes on any number of machines can share
//!   one work directory;
//! - the pack is assembled from the item files in the canonical order
//!   ([`crate::write::assemble`]), so a single run, a resumed run and a merge of shards give
//!   the same bytes.
//!
//! The work directory also holds `plan.json`: every process checks that its own plan is the
//! same, so items of different inputs are never mixed.
//!
//! Item file layout (little endian): `b"PBW3"` (pack 3.0's chunks, whose lighting leaves the
//! sun to the runtime; a `PBW1` or `PBW2` file of an older baker is not done and is rendered
//! again), u32 chunk count, then per chunk u32 kind code,
//! u32 base view, u32 key, u64 uncompressed length (0: take it from the chunk), u64 xxh3
//! checksum, u64 length, the bytes.

use std::fmt;
use std::fs::{self, File};
use std::io::Write;
use std::path::{Path, PathBuf};
use std::str::FromStr;

use plenoptic_pack::ChunkKind;

use crate::error::{BakeError, Result};
use crate::plan::Plan;

/// A unit of rendering work.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum WorkItem {
    /// The range image of a base view at one of its time keys.
    RangeImage {
        /// Base view index.
        base_view: u32,
        /// Time key index.
        key: u32,
    },
    /// The temporal volume of a base view.
    Volume {
        /// Base view index.
        base_view: u32,
    },
}

impl WorkItem {
    /// The item's file stem, e.g. `range-b00003-k00001`.
    pub fn name(&self) -> String {
        match *self {
            WorkItem::RangeImage { base_view, key } => format!("range-b{base_view:05}-k{key:05}"),
            WorkItem::Volume { base_view } => format!("volume-b{base_view:05}"),
        }
    }
}

impl fmt::Display for WorkItem {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.name())
    }
}

/// Every work item of a plan in canonical order: per base view, its range images by key,
/// then its volume (when it has a budget).
pub fn work_items(plan: &Plan) -> Vec<WorkItem> {
    let mut out = Vec::new();
    for (bv, v) in plan.base_views.iter().enumerate() {
        for key in 0..v.time_keys.len() {
            out.push(WorkItem::RangeImage {
                base_view: bv as u32,
                key: key as u32,
            });
        }
        if v.volume_samples > 0 {
            out.push(WorkItem::Volume {
                base_view: bv as u32,
            });
        }
    }
    out
}

/// One shard of N: `index` in `0..count`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Shard {
    /// This shard, from 0.
    pub index: u32,
    /// Number of shards.
    pub count: u32,
}

impl Shard {
    /// Whether canonical item number `i` belongs to this shard.
    pub fn owns(&self, i: usize) -> bool {
        i % self.count as usize == self.index as usize
    }
}

impl FromStr for Shard {
    type Err = BakeError;

    /// Parses `i/N` (0 ≤ i < N).
    fn from_str(s: &str) -> Result<Self> {
        let bad = || BakeError::Invalid(format!("shard '{s}': expected i/N with 0 <= i < N"));
        let (i, n) = s.split_once('/').ok_or_else(bad)?;
        let index: u32 = i.trim().parse().map_err(|_| bad())?;
        let count: u32 = n.trim().parse().map_err(|_| bad())?;
        if count == 0 || index >= count {
            return Err(bad());
        }
        Ok(Shard { index, count })
    }
}

impl fmt::Display for Shard {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}/{}", self.index, self.count)
    }
}

/// One encoded chunk of a work item.
#[derive(Debug, Clone, PartialEq)]
pub struct ItemChunk {
    /// Chunk kind.
    pub kind: ChunkKind,
    /// Base view index.
    pub base_view: u32,
    /// Key (time key or bucket).
    pub key: u32,
    /// Uncompressed length, or 0 to read it from the chunk's own header.
    pub uncompressed_length: u64,
    /// The bytes.
    pub bytes: Vec<u8>,
}

const MAGIC: &[u8; 4] = b"PBW3";

/// The work directory of a bake.
#[derive(Debug, Clone)]
pub struct WorkDir {
    /// Its path.
    pub path: PathBuf,
}

impl WorkDir {
    /// The default work directory of `output`: `<output>.work`.
    pub fn for_output(output: &Path) -> Self {
        let mut name = output.as_os_str().to_owned();
        name.push(".work");
        WorkDir {
            path: PathBuf::from(name),
        }
    }

    /// Creates the directory (and parents).
    pub fn create(&self) -> Result<()> {
        fs::create_dir_all(&self.path).map_err(|e| BakeError::io(&self.path, e))
    }

    /// Removes the directory and everything in it (no error if it does not exist).
    pub fn remove(&self) -> Result<()> {
        match fs::remove_dir_all(&self.path) {
            Err(e) if e.kind() != std::io::ErrorKind::NotFound => Err(BakeError::io(&self.path, e)),
            _ => Ok(()),
        }
    }

    /// The file of `item`.
    pub fn item_path(&self, item: &WorkItem) -> PathBuf {
        self.path.join(format!("{}.chunks", item.name()))
    }

    /// Writes `plan.json`, or checks that the one there is the same plan.
    pub fn check_or_write_plan(&self, plan: &Plan) -> Result<()> {
        let path = self.path.join("plan.json");
        let json = plan.to_json();
        match fs::read_to_string(&path) {
            Ok(existing) => {
                if existing != json {
                    return Err(BakeError::WorkDir {
                        path: self.path.clone(),
                        problem: "its plan.json differs from this recipe's plan (recipe, scene or \
                                  settings changed); remove the directory or bake without \
                                  --resume"
                            .into(),
                    });
                }
                Ok(())
            }
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
                atomic_write(&path, json.as_bytes())?;
                Ok(())
            }
            Err(e) => Err(BakeError::io(path, e)),
        }
    }

    /// Reads `plan.json`.
    pub fn read_plan(&self) -> Result<Plan> {
        let path = self.path.join("plan.json");
        let text = fs::read_to_string(&path).map_err(|e| BakeError::io(&path, e))?;
        Plan::from_json(&text, &path)
    }

    /// Whether `item` has a complete, undamaged file.
    pub fn is_done(&self, item: &WorkItem) -> bool {
        self.read_item(item).is_ok()
    }

    /// Writes `item`'s chunks durably (temporary file, fsync, rename).
    pub fn write_item(&self, item: &WorkItem, chunks: &[ItemChunk]) -> Result<()> {
        let mut buf = Vec::new();
        buf.extend_from_slice(MAGIC);
        buf.extend_from_slice(&(chunks.len() as u32).to_le_bytes());
        for c in chunks {
            buf.extend_from_slice(&c.kind.code().to_le_bytes());
            buf.extend_from_slice(&c.base_view.to_le_bytes());
            buf.extend_from_slice(&c.key.to_le_bytes());
            buf.extend_from_slice(&c.uncompressed_length.to_le_bytes());
            buf.extend_from_slice(&plenoptic_pack::checksum(&c.bytes).to_le_bytes());
            buf.extend_from_slice(&(c.bytes.len() as u64).to_le_bytes());
            buf.extend_from_slice(&c.bytes);
        }
        atomic_write(&self.item_path(item), &buf)
    }

    /// Reads `item`'s chunks, checking layout and checksums.
    pub fn read_item(&self, item: &WorkItem) -> Result<Vec<ItemChunk>> {
        let path = self.item_path(item);
        let data = fs::read(&path).map_err(|e| BakeError::io(&path, e))?;
        let bad = |problem: &str| BakeError::WorkDir {
            path: path.clone(),
            problem: problem.to_owned(),
        };
        if data.len() < 8 || &data[..4] != MAGIC {
            return Err(bad("not a work item file"));
        }
        let count = u32::from_le_bytes(data[4..8].try_into().unwrap_or_default()) as usize;
        let mut at = 8usize;
        let mut out = Vec::new();
        let u32_at =
            |d: &[u8], a: usize| u32::from_le_bytes(d[a..a + 4].try_into().unwrap_or_default());
        let u64_at =
            |d: &[u8], a: usize| u64::from_le_bytes(d[a..a + 8].try_into().unwrap_or_default());
        for _ in 0..count {
            if data.len() < at + 36 {
                return Err(bad("truncated"));
            }
            let kind = ChunkKind::from_code(u32_at(&data, at));
            let base_view = u32_at(&data, at + 4);
            let key = u32_at(&data, at + 8);
            let uncompressed_length = u64_at(&data, at + 12);
            let sum = u64_at(&data, at + 20);
            let len = u64_at(&data, at + 28) as usize;
            at += 36;
            if data.len() - at < len {
                return Err(bad("truncated"));
            }
            let bytes = data[at..at + len].to_vec();
            at += len;
            if plenoptic_pack::checksum(&bytes) != sum {
                return Err(bad("checksum mismatch"));
            }
            out.push(ItemChunk {
                kind,
                base_view,
                key,
                uncompressed_length,
                bytes,
            });
        }
        if at != data.len() {
            return Err(bad("trailing bytes"));
        }
        Ok(out)
    }
}

/// Writes `bytes` to `path` through a temporary file in the same directory, fsynced, then
/// renamed over `path`.
pub fn atomic_write(path: &Path, bytes: &[u8]) -> Result<()> {
    let dir = path.parent().unwrap_or(Path::new("."));
    let mut tmp = tempfile::Builder::new()
        .prefix(".item.")
        .suffix(".tmp")
        .tempfile_in(dir)
        .map_err(|e| BakeError::io(dir, e))?;
    tmp.write_all(bytes).map_err(|e| BakeError::io(path, e))?;
    tmp.as_file()
        .sync_all()
        .map_err(|e| BakeError::io(path, e))?;
    tmp.persist(path)
        .map_err(|e| BakeError::io(path, e.error))?;
    #[cfg(unix)]
    if let Ok(d) = File::open(dir) {
        let _ = d.sync_all();
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shards_parse_and_partition() {
        let s: Shard = "1/3".parse().unwrap();
        assert_eq!(s, Shard { index: 1, count: 3 });
        assert_eq!(s.to_string(), "1/3");
        for bad in ["3/3", "1", "a/2", "0/0", "-1/2"] {
            assert!(bad.parse::<Shard>().is_err(), "{bad}");
        }
        let owners: Vec<u32> = (0..7)
            .map(|i| {
                (0..3)
                    .find(|&k| Shard { index: k, count: 3 }.owns(i))
                    .unwrap()
            })
            .collect();
        assert_eq!(owners, vec![0, 1, 2, 0, 1, 2, 0]);
    }

    #[test]
    fn item_files_round_trip_and_damage_is_detected() {
        let dir = tempfile::tempdir().unwrap();
        let work = WorkDir {
            path: dir.path().join("x.pack.work"),
        };
        work.create().unwrap();
        let item = WorkItem::RangeImage {
            base_view: 2,
            key: 1,
        };
        assert!(!work.is_done(&item));
        let chunks = vec![ItemChunk {
            kind: ChunkKind::VolumeBlock,
            base_view: 2,
            key: 7,
            uncompressed_length: 99,
            bytes: vec![1, 2, 3, 4, 5],
        }];
        work.write_item(&item, &chunks).unwrap();
        assert!(work.is_done(&item));
        assert_eq!(work.read_item(&item).unwrap(), chunks);
        let path = work.item_path(&item);
        let mut bytes = fs::read(&path).unwrap();
        bytes.pop();
        fs::write(&path, &bytes).unwrap();
        assert!(!work.is_done(&item), "a truncated item is not done");
        work.remove().unwrap();
        assert!(!work.path.exists());
    }
}
