//! Sets and decks on the atlas's mean mesh.

use crate::error::{Error, Result};
use crate::geometry::Point;
use crate::mesh::FeMesh;
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
    check_deck_mesh(&atlas.mesh, "the atlas's mean mesh", deck, path)
}

/// Checks that a deck's mesh has the elements and node count of `mesh` (`what` names it in
/// the error): a subject's morphed mesh has those of the atlas's mean mesh, so that the
/// deck's copy with the subject's node coordinates is the subject's model.
pub fn check_deck_mesh<const D: usize>(
    mesh: &FeMesh<D>,
    what: &str,
    deck: &crate::formats::Deck,
    path: &Path,
) -> Result<()> {
    let deck = deck.mesh();
    if deck.nodes.len() != mesh.nodes.len()
        || deck.kind != mesh.kind
        || deck.connectivity != mesh.connectivity
    {
        return Err(Error::parse(
            path,
            0,
            format!(
                "the deck's mesh ({} nodes, {} {} elements) is not {what} ({} nodes, {} {} elements); start the deck from `atlasmesh convert ATLAS mean.inp` (or `mean.feb`)",
                deck.nodes.len(),
                deck.num_elements(),
                deck.kind.name(),
                mesh.nodes.len(),
                mesh.num_elements(),
                mesh.kind.name()
            ),
        ));
    }
    Ok(())
}
