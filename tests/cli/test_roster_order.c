/* test_roster_order.c - the order a catalog bake hands its types to the threads: longest
 * first, so no long type is left running alone at the end (cli/roster/roster_order.c). The order
 * changes no output: test_catalog compares -j 1 with -j 4 byte for byte. */
#include "testutil.h"

#include "roster/roster_files.h"

#define TMP TEST_TMP "/roster_order"

/* Before preparing, a type's cost is its model file's size. */
static void test_before_preparing_the_biggest_file_goes_first(void **state)
{
    (void)state;
    assert_int_equal(system("mkdir -p " TMP), 0);
    static const size_t sizes[5] = {10, 3000, 10, 70000, 500};
    cb_catalog_animal animals[5];
    cb_roster_type types[5];
    memset(animals, 0, sizeof animals), memset(types, 0, sizeof types);
    char paths[5][64];
    for (int i = 0; i < 5; ++i) {
        snprintf(paths[i], sizeof paths[i], TMP "/m%d.glb", i);
        char *text = malloc(sizes[i] + 1);
        memset(text, 'x', sizes[i]), text[sizes[i]] = 0;
        write_text(paths[i], text);
        free(text);
        animals[i].model = paths[i];
        types[i].rows = 1000 - i; /* not used before preparing */
    }
    cb_catalog cat = {0};
    cat.animals = animals, cat.animal_count = 5;
    cb_roster r = {0};
    r.types = types, r.type_count = 5;
    uint32_t order[5];
    roster_order_types(&cat, &r, false, order);
    static const uint32_t want[5] = {3, 1, 4, 0, 2}; /* equal sizes keep catalog order */
    for (int i = 0; i < 5; ++i) assert_int_equal(order[i], want[i]);
}

/* After preparing: rows x (vertices + 16 bones), what sampling, skinning and measuring cost. */
static void test_after_preparing_rows_times_vertices_and_bones(void **state)
{
    (void)state;
    cb_catalog_animal animals[4];
    cb_roster_type types[4];
    memset(animals, 0, sizeof animals), memset(types, 0, sizeof types);
    for (int i = 0; i < 4; ++i) animals[i].model = TMP "/none.glb";
    types[0] = (cb_roster_type){.rows = 100, .vertices = 1000, .bones = 10};  /* 116,000 */
    types[1] = (cb_roster_type){.rows = 300, .vertices = 100, .bones = 40};   /* 222,000 */
    types[2] = (cb_roster_type){.rows = 10, .vertices = 5000, .bones = 50};   /*  58,000 */
    types[3] = (cb_roster_type){.rows = 1000, .vertices = 200, .bones = 2};   /* 232,000 */
    cb_catalog cat = {0};
    cat.animals = animals, cat.animal_count = 4;
    cb_roster r = {0};
    r.types = types, r.type_count = 4;
    uint32_t order[4];
    roster_order_types(&cat, &r, true, order);
    static const uint32_t want[4] = {3, 1, 0, 2};
    for (int i = 0; i < 4; ++i) assert_int_equal(order[i], want[i]);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_before_preparing_the_biggest_file_goes_first),
        cmocka_unit_test(test_after_preparing_rows_times_vertices_and_bones),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
