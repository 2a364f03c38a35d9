//! Sets and decks on the atlas's mean mesh.

use crate::error::{Error, Result};
use crate::geometry::Point;
use crate::model::Atlas;
use std::path::Path;

/// Adds the sets of `config` (evaluated on the mean mesh, with the atlas's landmarks) to the
/// atlas's mesh; a set of the same name is replaced.
pub fn apply_sets<const D: usize>(
    atlas: &mut Atlas<D>,
    config: &crate::mesh::sets::SetsConfig,
) -> Result<()> {
    let landmarks: Vec<Point<D>> = atlas.landmarks.iter().map(|&i| atlas.mean[i]).collect();
    let s = config.evaluate(&atlas.mesh, &landmarks)?;
    atlas.mesh.sets.merge(s);
    Ok(())
}

/// Checks that a deck's mesh is the atlas's mean mesh (same elements and node count).
pub fn check_deck<const D: usize>(
    atlas: &Atlas<D>,
    deck: &crate::formats::Deck,
    path: &Path,
) -> Result<()> {
    let deck = deck.mesh();
    if deck.nodes.len() != atlas.mesh.nodes.len()
        || deck.kind != atlas.mesh.kind
        || deck.connectivity != atlas.mesh.connectivity
    {
        return Err(Error::parse(
            path,
            0,
            format!(
                "the deck's mesh ({} nodes, {} {} elements) is not the atlas's mean mesh ({} nodes, {} {} elements); start the deck from `atlasmesh convert ATLAS mean.inp` (or `mean.feb`)",
                deck.nodes.len(),
                deck.num_elements(),
                deck.kind.name(),
                atlas.mesh.nodes.len(),
                atlas.mesh.num_elements(),
                atlas.mesh.kind.name()
            ),
        ));
    }
    Ok(())
}
