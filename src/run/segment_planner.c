/* The segment planner's thread and ring: see segment_planner.h. */
#include "run/segment_planner.h"
#include "host_clock.h"

#include <pthread.h>
#include <stdlib.h>

struct evr_planner {
    evr_planned_segment slot[EVR_PLANNER_SLOTS];
    int num_segments;
    evr_plan_fn fn;
    void *user;
    pthread_t thread;
    int started;
    pthread_mutex_t mu;
    pthread_cond_t cv;
    int planned;  /* segments 0 .. planned - 1 are planned */
    int released; /* the slots of segments 0 .. released - 1 are free again */
    int stop;
    double busy; /* seconds in fn */
};

static void plan_one(evr_planner *p, int i)
{
    const double t = evr_host_seconds();
    p->fn(p->user, i, &p->slot[i % EVR_PLANNER_SLOTS]);
    const double dt = evr_host_seconds() - t;
    pthread_mutex_lock(&p->mu);
    p->busy += dt;
    p->planned = i + 1;
    pthread_cond_broadcast(&p->cv);
    pthread_mutex_unlock(&p->mu);
}

static void *planner_main(void *arg)
{
    evr_planner *p = arg;
    for (int i = 0; i < p->num_segments; i++) {
        pthread_mutex_lock(&p->mu);
        while (!p->stop && i - p->released >= EVR_PLANNER_SLOTS) pthread_cond_wait(&p->cv, &p->mu);
        const int stop = p->stop;
        pthread_mutex_unlock(&p->mu);
        if (stop) break;
        plan_one(p, i);
    }
    return NULL;
}

evr_planner *evr_planner_start(int num_segments, size_t keys_cap, int num_tracks, evr_plan_fn fn,
                               void *user)
{
    evr_planner *p = calloc(1, sizeof *p);
    if (!p) return NULL;
    if (pthread_mutex_init(&p->mu, NULL) != 0) {
        free(p);
        return NULL;
    }
    pthread_cond_init(&p->cv, NULL);
    p->num_segments = num_segments;
    p->fn = fn;
    p->user = user;
    for (int s = 0; s < EVR_PLANNER_SLOTS; s++) {
        p->slot[s].keys = malloc(sizeof *p->slot[s].keys * (keys_cap ? keys_cap : 1));
        p->slot[s].track_offset = malloc(sizeof(int) * (size_t)(num_tracks > 0 ? num_tracks : 1));
        p->slot[s].track_count = malloc(sizeof(int) * (size_t)(num_tracks > 0 ? num_tracks : 1));
        if (!p->slot[s].keys || !p->slot[s].track_offset || !p->slot[s].track_count) {
            evr_planner_stop(p);
            return NULL;
        }
    }
    p->started = pthread_create(&p->thread, NULL, planner_main, p) == 0;
    return p;
}

const evr_planned_segment *evr_planner_take(evr_planner *p, int segment)
{
    if (!p->started) {
        if (p->planned <= segment) plan_one(p, segment);
    } else {
        pthread_mutex_lock(&p->mu);
        while (p->planned <= segment) pthread_cond_wait(&p->cv, &p->mu);
        pthread_mutex_unlock(&p->mu);
    }
    return &p->slot[segment % EVR_PLANNER_SLOTS];
}

void evr_planner_release(evr_planner *p, int segment)
{
    pthread_mutex_lock(&p->mu);
    if (segment + 1 > p->released) p->released = segment + 1;
    pthread_cond_broadcast(&p->cv);
    pthread_mutex_unlock(&p->mu);
}

double evr_planner_busy_seconds(evr_planner *p)
{
    pthread_mutex_lock(&p->mu);
    const double b = p->busy;
    pthread_mutex_unlock(&p->mu);
    return b;
}

void evr_planner_stop(evr_planner *p)
{
    if (!p) return;
    if (p->started) {
        pthread_mutex_lock(&p->mu);
        p->stop = 1;
        pthread_cond_broadcast(&p->cv);
        pthread_mutex_unlock(&p->mu);
        pthread_join(p->thread, NULL);
    }
    pthread_cond_destroy(&p->cv);
    pthread_mutex_destroy(&p->mu);
    for (int s = 0; s < EVR_PLANNER_SLOTS; s++) {
        free(p->slot[s].keys);
        free(p->slot[s].track_offset);
        free(p->slot[s].track_count);
        evr_deform_keys_free(&p->slot[s].deform);
    }
    free(p);
}
