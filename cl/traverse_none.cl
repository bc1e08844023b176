/* traverse_none.cl: every object in id order (the study's "no tree"). */
#if KDRT_TRAVERSAL == 0
KDRT_INLINE void traverse(const Scene* scene, const Ray* ray, real t_max, bool any_hit, Hit* best) {
    const uint count = scene->sphere_count + scene->triangle_count;
    for (uint id = 0; id < count; ++id) {
        intersect_object(scene, ray, id, best);
        if (any_hit && best->t < t_max) return;
    }
}
#endif
