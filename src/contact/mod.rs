//! Wheel–rail rolling contact.
