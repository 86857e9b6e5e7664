//! Local Terrain Map Manager: elevation, uncertainty, footfall and slope maps.
